"""The position controller's law (7.21-7.22) compiled with numba: PD, the tabulated and the exact model.

:meth:`controller.position.PositionController.step` spends ~20 µs per sample in Python
(scalar kinematics, the numpy bilinear interpolation, the law).  :func:`law_step` does the
same sample in one compiled call taking plain floats: the reference checks, the scalar
kinematics of :mod:`controller.kinematics` (inverse and direct kinematics, J, beta, the
joint references), the bilinear interpolation of :class:`controller.model.TabulatedModel`,
the law (7.21-7.22) with sat, the adaptive gain (6.66) and the integral, the torques and the
current references.  Every expression is written in the same order as the Python reference
(:meth:`PositionController.step_reference`), so both agree to round-off
(``tests/test_controller_fast.py``: ~1e-12 relative over random states, all ten strategies;
seed 001's law, ``B_LAW``, in :func:`_component`).

One float64 array ``buf`` carries the constants, the controller's state and the table
(numba's dispatcher costs ~0.3 µs per array argument, ~30 ns per float): layout below,
built by :func:`pack`.

Refusals stay in Python: where the reference would raise (non-finite input, reference
outside the workspace or in the near-singular band, measured pose without assembly, a
point outside the table or in a cell with a left-out corner, a division by zero),
:func:`law_step` returns status 1 WITHOUT touching the state, and the caller runs the
Python reference with the same inputs, which raises the same error with its message (or,
should the two ever disagree on a boundary, returns the reference's result).

The module calls no compiled function of another file, so numba's on-disk cache
(``cache=True``, invalidated by this file's modification time only) cannot go stale.
:func:`compile_law` compiles :func:`law_step` for its one signature on first use.
"""
from __future__ import annotations

import math

import numpy as np
import threading

from numba import float64, njit, types

# --- layout of buf ---------------------------------------------------------------------
B_L0, B_L11, B_L12, B_L21, B_L22 = 0, 1, 2, 3, 4     # geometry, m
B_BAND = 5                                           # near-singular band of the reference
B_SPACE = 6                                          # 0: joint space (q), 1: task space (x)
B_MODEL = 7                                          # 0: PD (Ĥ = m*·1, ĥ = 0), 1: tabulated, 2: exact
B_KP, B_KV, B_PHI = 8, 9, 10
B_ADAPT = 11                                         # 1: adaptive gain (6.66)
B_GAMMA = 12                                         # gamma1, gamma2
B_MSTAR = 14
B_KT = 15                                            # kt1, kt2
B_TX0, B_TY0, B_TINV, B_TNX, B_TNY = 17, 18, 19, 20, 21   # table: first grid point, 1/step, cells
#: The controller's state: integral (2), k (2), s_prev (2), s (2), e (2).
S_INTEGRAL, S_K, S_S_PREV, S_S, S_E = 22, 24, 26, 28, 30
STATE = slice(22, 32)
B_LAW = 32                                           # 0: unified law (7.21-7.22), 1: seed 001's
#: First entry of the table, shape (ny + 1, nx + 1, N_TERMS) flattened row-major.
B_TABLE = 33


def run_state_words(buf):
    """The indices of ``buf`` a run changes (:data:`STATE`); every other word is configuration
    (modes the kernel branches on, the table's cells it indexes with, gains, the table), which
    a restored FMU state may not change (:mod:`fmus.fmustate`)."""
    return range(STATE.start, STATE.stop)

SPACE_Q, SPACE_X = 0.0, 1.0
MODEL_PD, MODEL_TABULATED, MODEL_EXACT = 0.0, 1.0, 2.0
OK, REFUSED = 0.0, 1.0
LAW_UNIFIED, LAW_SEED = 0.0, 1.0


def pack(kin, band, space, model, kp, kv, phi, gamma, m_star, kt, law="unified"):
    """The ``buf`` of :func:`law_step`, state zero (:func:`reset_state` sets k).

    Parameters
    ----------
    kin : controller.kinematics.Kinematics
    band : float
    space : {"q", "x"}
    model : TabulatedModel, ExactModel or None
        None: the PD law; an ExactModel: the terms come from the caller
        (:func:`law_terms_step`).
    kp, kv, phi, m_star : float
    gamma : tuple or None
    kt : (float, float)
    law : {"unified", "seed001"}
        :attr:`controller.strategies.Strategy.law`.
    """
    exact = model is not None and model.kind == "exact"
    if model is None or exact:
        n_table = 0
    else:
        table = np.ascontiguousarray(model.table, dtype=np.float64)
        n_table = table.size
    buf = np.zeros(B_TABLE + n_table)
    buf[B_L0:B_L22 + 1] = (kin.l0, kin.l11, kin.l12, kin.l21, kin.l22)
    buf[B_BAND] = band
    buf[B_SPACE] = SPACE_X if space == "x" else SPACE_Q
    buf[B_MODEL] = MODEL_PD if model is None else (MODEL_EXACT if exact else MODEL_TABULATED)
    buf[B_KP], buf[B_KV], buf[B_PHI] = kp, kv, phi
    if gamma is not None:
        buf[B_ADAPT] = 1.0
        buf[B_GAMMA:B_GAMMA + 2] = gamma
    buf[B_MSTAR] = m_star
    buf[B_KT:B_KT + 2] = kt
    buf[B_LAW] = LAW_SEED if law == "seed001" else LAW_UNIFIED
    if n_table:
        buf[B_TX0], buf[B_TY0], buf[B_TINV] = model._x0, model._y0, model._inv
        buf[B_TNX], buf[B_TNY] = model._nx, model._ny
        buf[B_TABLE:] = table.ravel()
    return buf


@njit(cache=True, error_model="numpy")
def _sign(x):
    return 0.0 if x == 0.0 else math.copysign(1.0, x)


@njit(cache=True, error_model="numpy")
def _sat(x):
    return x if -1.0 <= x <= 1.0 else (1.0 if x > 0.0 else -1.0)


@njit(cache=True, error_model="numpy")
def _chain_ik(l1, l2, px, py, elbow_sign):
    """(ok, phi1, phi2): :func:`controller.kinematics._chain_ik`."""
    r2 = px * px + py * py
    cos_b = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    if not -1.0 <= cos_b <= 1.0:
        return False, 0.0, 0.0
    beta = elbow_sign * math.acos(cos_b)
    phi1 = math.atan2(py, px) - math.atan2(l2 * math.sin(beta), l1 + l2 * math.cos(beta))
    return True, phi1, phi1 + beta


@njit(cache=True, error_model="numpy")
def _jacobians(l0, l11, l21, x, y, q1, q2):
    """:meth:`Kinematics.jacobians`: J_X = [[a, b], [c, d]], J_Theta = diag(t1, t2)."""
    c1, s1, c2, s2 = math.cos(q1), math.sin(q1), math.cos(q2), math.sin(q2)
    a = x - l0 - l11 * c1
    b = y - l11 * s1
    c = x + l0 - l21 * c2
    d = y - l21 * s2
    t1 = l11 * ((x - l0) * s1 - y * c1)
    t2 = l21 * ((x + l0) * s2 - y * c2)
    return a, b, c, d, t1, t2


@njit(cache=True, error_model="numpy")
def _bias_rhs(l0, l11, l21, x, y, q1, q2, dx, dy, dq1, dq2):
    """:meth:`Kinematics._bias_rhs`: dJ_X dx + dJ_Theta dq."""
    c1, s1, c2, s2 = math.cos(q1), math.sin(q1), math.cos(q2), math.sin(q2)
    da1x, da1y = -l11 * dq1 * s1, l11 * dq1 * c1
    da2x, da2y = -l21 * dq2 * s2, l21 * dq2 * c2
    r1 = (dx - da1x) * dx + (dy - da1y) * dy
    r2 = (dx - da2x) * dx + (dy - da2y) * dy
    r1 += l11 * (dx * s1 + (x - l0) * c1 * dq1 - dy * c1 + y * s1 * dq1) * dq1
    r2 += l21 * (dx * s2 + (x + l0) * c2 * dq2 - dy * c2 + y * s2 * dq2) * dq2
    return r1, r2


@njit(cache=True, error_model="numpy")
def _forward(l0, l11, l12, l21, l22, q1, q2):
    """(ok, x, y): :meth:`Kinematics.forward`."""
    a1x, a1y = l0 + l11 * math.cos(q1), l11 * math.sin(q1)
    a2x, a2y = -l0 + l21 * math.cos(q2), l21 * math.sin(q2)
    dx, dy = a1x - a2x, a1y - a2y
    dist2 = dx * dx + dy * dy
    dist = math.sqrt(dist2)
    r1, r2 = l12, l22
    if dist == 0.0 or dist > r1 + r2 or dist < abs(r1 - r2):
        return False, 0.0, 0.0
    along = (dist2 + r2 * r2 - r1 * r1) / (2.0 * dist)
    height = math.sqrt(max(r2 * r2 - along * along, 0.0))
    ux, uy = dx / dist, dy / dist
    return True, a2x + along * ux - height * uy, a2y + along * uy + height * ux


@njit(cache=True, error_model="numpy")
def _interpolate(buf, x, y, out):
    """:meth:`TabulatedModel.interpolate` into out (N_TERMS); False where it raises."""
    nx, ny = buf[B_TNX], buf[B_TNY]
    fx = (x - buf[B_TX0]) * buf[B_TINV]
    fy = (y - buf[B_TY0]) * buf[B_TINV]
    if not (0.0 <= fx < nx + 1.0 and 0.0 <= fy < ny + 1.0):   # the reference's index test fails too
        return False
    ix, iy = int(math.floor(fx)), int(math.floor(fy))
    if ix == nx and fx - ix < 1e-9:
        ix -= 1
    if iy == ny and fy - iy < 1e-9:
        iy -= 1
    if not (0 <= ix < nx and 0 <= iy < ny):
        return False
    n = out.size
    row = (int(nx) + 1) * n
    i00 = B_TABLE + iy * row + ix * n       # corners c[0, 0], c[0, 1], c[1, 0], c[1, 1]
    i01 = i00 + n
    i10 = i00 + row
    i11 = i10 + n
    if (math.isnan(buf[i00]) or math.isnan(buf[i01]) or math.isnan(buf[i10])
            or math.isnan(buf[i11])):
        return False                        # cell_ok: all four corners present
    wx, wy = fx - ix, fy - iy
    for j in range(n):
        out[j] = ((1.0 - wy) * ((1.0 - wx) * buf[i00 + j] + wx * buf[i01 + j])
                  + wy * ((1.0 - wx) * buf[i10 + j] + wx * buf[i11 + j]))
    return True


@njit(cache=True, error_model="numpy")
def _component(buf, i, e, de, dde, ddr_d, h):
    """The law (7.21-7.22) on component i: updates the state, returns the commanded acceleration.

    Seed 001's law (:data:`LAW_SEED`, section 1.2, docs/controller.md): s = de + lam e,
    a = ddr_d + lam de + k sat(s/phi), no integral (lam = kv / 2)."""
    seed = buf[B_LAW] == LAW_SEED
    if seed:
        lam = 0.5 * buf[B_KV]
        feedback = lam * de
        s = de + lam * e                                                  # seed 001: -s
    else:
        feedback = buf[B_KV] * de + buf[B_KP] * e
        s = dde + feedback                                                # (7.22)
    phi = buf[B_PHI]
    if buf[B_ADAPT] != 0.0:                                               # (6.66)
        s_prev = buf[S_S_PREV + i]
        same = _sign(s) == _sign(s_prev)
        if abs(s) >= phi or not same:
            buf[S_K + i] = abs(buf[S_K + i] + buf[B_GAMMA + i] * _sign(s) * _sign(s_prev))
    k = buf[S_K + i]
    buf[S_S_PREV + i] = s
    buf[S_S + i] = s
    buf[S_E + i] = e
    if seed:
        return ddr_d + feedback + k * _sat(s / phi)
    if k != 0.0:
        buf[S_INTEGRAL + i] += h * k * _sat(s / phi)
    return ddr_d + feedback + buf[S_INTEGRAL + i]                         # (7.21)


@njit(cache=True, error_model="numpy")
def _measured(buf, q1, q2, dq1, dq2):
    """(ok, x, y, dx, dy, (a, b, c, d, det), J) of the measurement (:meth:`Kinematics.task_state`):
    J_X = [[a, b], [c, d]], its determinant, J = -J_X^-1 J_Theta; ok False without assembly or
    for a singular J_X."""
    l0, l11, l12, l21, l22 = buf[B_L0], buf[B_L11], buf[B_L12], buf[B_L21], buf[B_L22]
    ok, x, y = _forward(l0, l11, l12, l21, l22, q1, q2)
    if not ok:
        return False, 0.0, 0.0, 0.0, 0.0, (0.0, 0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)
    a, b, c, d, t1, t2 = _jacobians(l0, l11, l21, x, y, q1, q2)
    det = a * d - b * c
    if det == 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, (0.0, 0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)
    J00, J01, J10, J11 = -d * t1 / det, b * t2 / det, c * t1 / det, -a * t2 / det
    return True, x, y, J00 * dq1 + J01 * dq2, J10 * dq1 + J11 * dq2, (a, b, c, d, det), (J00, J01, J10, J11)


@njit(cache=True, error_model="numpy")
def _link_rates(l1, l2, p1, p2, dx, dy):
    """:func:`controller.kinematics._link_rates`: l1 w1 n(p1) + l2 w2 n(p2) = (dx, dy)."""
    m00, m01 = -l1 * math.sin(p1), -l2 * math.sin(p2)
    m10, m11 = l1 * math.cos(p1), l2 * math.cos(p2)
    det = m00 * m11 - m01 * m10
    return (m11 * dx - m01 * dy) / det, (-m10 * dx + m00 * dy) / det


@njit(cache=True, error_model="numpy")
def exact_state(buf, q1, q2, dq1, dq2, q, dq):
    """The thesis coordinates q (7.12) and dq = C dq# (5.56) of the measured pose, where the
    exact model evaluates its terms (:meth:`controller.model.ExactModel.full_state` at the
    :meth:`Kinematics.task_state` of the measurement).  False where those would raise (no
    assembly, a singular J_X, out of reach): the law then refuses the sample."""
    l0, l11, l12, l21, l22 = buf[B_L0], buf[B_L11], buf[B_L12], buf[B_L21], buf[B_L22]
    ok, x, y, dx, dy, _, _ = _measured(buf, q1, q2, dq1, dq2)
    if not ok:
        return False
    ok1, p11, p12 = _chain_ik(l11, l12, x - l0, y, 1.0)
    ok2, p21, p22 = _chain_ik(l21, l22, x + l0, y, -1.0)
    if not (ok1 and ok2):
        return False
    q[0], q[1], q[2], q[3], q[4], q[5], q[6] = x, y, 0.0, p11, p12 - p11, math.pi - p21, p21 - p22
    w11, w12 = _link_rates(l11, l12, p11, p12, dx, dy)
    w21, w22 = _link_rates(l21, l22, p21, p22, dx, dy)
    dq[0], dq[1], dq[2], dq[3], dq[4], dq[5], dq[6] = dx, dy, 0.0, w11, w12 - w11, -w21, w21 - w22
    return True


#: The one signature of :func:`law_step` (:func:`compile_law`).
LAW_SIGNATURE = types.UniTuple(float64, 7)(float64[::1], *([float64] * 13))
#: ... of :func:`law_terms_step` and :func:`exact_state` (the exact model).
LAW_TERMS_SIGNATURE = types.UniTuple(float64, 7)(float64[::1], *([float64] * 13), float64[::1])
EXACT_STATE_SIGNATURE = types.boolean(float64[::1], *([float64] * 4), float64[::1], float64[::1])


#: Serialises :func:`compile_law`: two controllers initialised at once from two threads
#: would otherwise both see no signature, and the second compile the disabled dispatcher.
_COMPILE_LOCK = threading.Lock()


def compile_law(exact: bool = False):
    """Compile :func:`law_step` (or load it from numba's cache) for :data:`LAW_SIGNATURE` only
    (with ``exact``, also :func:`law_terms_step` and :func:`exact_state` for theirs).

    Called by the first controller that uses it (~3 s the first time, ~0.5 s from the cache).
    Afterwards the dispatcher compiles nothing more: ints or bools passed by a caller are
    converted to float64 instead of triggering a compilation per type combination.
    Thread-safe: a second thread waits for the first one's compilation.
    """
    if not hasattr(law_step, "signatures"):
        return                  # NUMBA_DISABLE_JIT=1 (the mutation campaign): plain Python
    with _COMPILE_LOCK:
        functions = ((law_step, LAW_SIGNATURE),) + (((law_terms_step, LAW_TERMS_SIGNATURE),
                                                      (exact_state, EXACT_STATE_SIGNATURE)) if exact else ())
        for function, signature in functions:
            if not function.signatures:
                function.compile(signature.args)
                function.disable_compile()


#: No model terms (PD and tabulated laws).
_NO_TERMS = np.zeros(0)


@njit(cache=True, error_model="numpy")
def law_step(buf, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, h):
    """One sample of the law (7.21-7.22): (tau1, tau2, i_ref1, i_ref2, e1, e2, status).

    status 0 (:data:`OK`): outputs valid, state advanced; 1 (:data:`REFUSED`): the Python
    reference would raise; state untouched, outputs 0.
    """
    return _law(buf, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, h, _NO_TERMS)


@njit(cache=True, error_model="numpy")
def law_terms_step(buf, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, h, terms):
    """:func:`law_step` of the exact model: ``terms`` are ``plant.fast5r.inverse_terms`` (layout
    INVERSE_*: M_M, v_M, g_M, Z) at the measured pose's :func:`exact_state`."""
    return _law(buf, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, h, terms)


@njit(cache=True, error_model="numpy")
def _law(buf, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, h, terms):
    refused = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, REFUSED)
    if not (math.isfinite(q1) and math.isfinite(q2) and math.isfinite(dq1) and math.isfinite(dq2)
            and math.isfinite(ddq1) and math.isfinite(ddq2) and math.isfinite(x_d) and math.isfinite(y_d)
            and math.isfinite(dx_d) and math.isfinite(dy_d) and math.isfinite(ddx_d)
            and math.isfinite(ddy_d)):
        return refused
    l0, l11, l12, l21, l22 = buf[B_L0], buf[B_L11], buf[B_L12], buf[B_L21], buf[B_L22]
    # Reference: inverse kinematics and singularity margin (PositionController._reference_angles).
    ok1, p11, p12 = _chain_ik(l11, l12, x_d - l0, y_d, 1.0)
    ok2, p21, p22 = _chain_ik(l21, l22, x_d + l0, y_d, -1.0)
    if not (ok1 and ok2):
        return refused
    margin = min(abs(math.sin(p12 - p11)), abs(math.sin(p22 - p21)), abs(math.sin(p12 - p22)))
    if margin < buf[B_BAND]:
        return refused
    # Measured task state (Kinematics.task_state).
    ok, x, y, dx, dy, jac, J = _measured(buf, q1, q2, dq1, dq2)
    if not ok:
        return refused
    a, b, c, d, det = jac
    J00, J01, J10, J11 = J
    r1, r2 = _bias_rhs(l0, l11, l21, x, y, q1, q2, dx, dy, dq1, dq2)
    beta0, beta1 = -(d * r1 - b * r2) / det, -(-c * r1 + a * r2) / det
    ddx = J00 * ddq1 + J01 * ddq2 + beta0
    ddy = J10 * ddq1 + J11 * ddq2 + beta1
    task = buf[B_SPACE] == SPACE_X
    if task:
        r = (x, y, dx, dy, ddx, ddy)
        rd = (x_d, y_d, dx_d, dy_d, ddx_d, ddy_d)
    else:
        r = (q1, q2, dq1, dq2, ddq1, ddq2)
        # Kinematics.joint_reference at the reference's angles.
        ra, rb, rc, rdd, rt1, rt2 = _jacobians(l0, l11, l21, x_d, y_d, p11, p21)
        if rt1 == 0.0 or rt2 == 0.0:
            return refused
        rdq1 = -(ra * dx_d + rb * dy_d) / rt1
        rdq2 = -(rc * dx_d + rdd * dy_d) / rt2
        rr1, rr2 = _bias_rhs(l0, l11, l21, x_d, y_d, p11, p21, dx_d, dy_d, rdq1, rdq2)
        rddq1 = -(ra * ddx_d + rb * ddy_d + rr1) / rt1
        rddq2 = -(rc * ddx_d + rdd * ddy_d + rr2) / rt2
        rd = (p11, p21, rdq1, rdq2, rddq1, rddq2)
    kind = buf[B_MODEL]
    m = np.empty(11)
    if kind == MODEL_TABULATED and not _interpolate(buf, x, y, m):      # TabulatedModel.terms
        return refused
    # The state changes from here on: no refusal below.
    a0 = _component(buf, 0, rd[0] - r[0], rd[2] - r[2], rd[4] - r[4], rd[4], h)
    a1 = _component(buf, 1, rd[1] - r[1], rd[3] - r[3], rd[5] - r[5], rd[5], h)
    if kind == MODEL_PD:                                                # PD: Ĥ = m*·1, ĥ = 0
        u0, u1 = buf[B_MSTAR] * a0, buf[B_MSTAR] * a1
        if task:
            tau1, tau2 = J00 * u0 + J10 * u1, J01 * u0 + J11 * u1      # tau = J^T u'
        else:
            tau1, tau2 = u0, u1
    else:
        if kind == MODEL_TABULATED:
            H00, H01, H11 = m[0], m[1], m[2]
            xx, yy, xy = dx * dx, dy * dy, dx * dy
            h0 = m[3] * xx + m[5] * yy + m[7] * xy + m[9]
            h1 = m[4] * xx + m[6] * yy + m[8] * xy + m[10]
        else:                                                           # exact: M_M, v_M + g_M (5.74-5.77)
            H00, H01, H11 = terms[0], terms[1], terms[3]
            h0, h1 = terms[4] + terms[6], terms[5] + terms[7]
        if task:
            u0, u1 = H00 * a0 + H01 * a1 + h0, H01 * a0 + H11 * a1 + h1  # (7.21)
            if kind == MODEL_EXACT:                                     # u' = Z^T u* (5.72)
                z00, z01, z10, z11 = terms[8], terms[9], terms[10], terms[11]
                det = z00 * z11 - z01 * z10
                us0 = (z11 * u0 - z10 * u1) / det
                us1 = (-z01 * u0 + z00 * u1) / det
                tau1, tau2 = us0, -us1                                  # tau2 = -u*_theta21
            else:
                tau1, tau2 = J00 * u0 + J10 * u1, J01 * u0 + J11 * u1
        else:                                                           # u' = J^T (H (J a + beta) + h)
            ax = J00 * a0 + J01 * a1 + beta0
            ay = J10 * a0 + J11 * a1 + beta1
            f0, f1 = H00 * ax + H01 * ay + h0, H01 * ax + H11 * ay + h1
            tau1, tau2 = J00 * f0 + J10 * f1, J01 * f0 + J11 * f1
    return (tau1, tau2, tau1 / buf[B_KT], tau2 / buf[B_KT + 1], buf[S_E], buf[S_E + 1], OK)


#: Status of :func:`law_io` when the law's outputs are not finite (the state is restored).
NONFINITE_OUTPUT = 2.0


@njit(cache=True, error_model="numpy")
def law_io(buf, x, h):
    """PositionController in the compiled scene loop (fmus.compiled):
    x = [q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d | tau1, tau2, i_ref1, i_ref2, e1, e2].

    Returns :data:`OK`, :data:`REFUSED` (nothing changed: the Python controller takes the
    sample, to raise its message or to use the exact model off the table) or
    :data:`NONFINITE_OUTPUT` (the slave refuses; the state is put back).
    """
    return _io(buf, x, h, _NO_TERMS)


@njit(cache=True, error_model="numpy")
def law_terms_io(buf, x, h, terms):
    """:func:`law_io` of the exact model, its ``terms`` as :func:`law_terms_step`."""
    return _io(buf, x, h, terms)


@njit(cache=True, error_model="numpy")
def _io(buf, x, h, terms):
    saved = buf[STATE].copy()
    r = _law(buf, x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], x[9], x[10], x[11], h, terms)
    if r[6] != OK:
        return REFUSED
    if not math.isfinite(r[0] + r[1] + r[2] + r[3] + r[4] + r[5]):
        buf[STATE] = saved
        return NONFINITE_OUTPUT
    for k in range(6):
        x[12 + k] = r[k]
    return OK
