"""TRANSITIONAL: the numba copy of the 5R kernel that fmus.compiled's generated loop still calls.

The product's 5R kernel is C (``kernels/src/fivebar.c``, bound by :mod:`plant.fast5r`); the
generated loop of ``--mode compiled`` (fmus/adapters.py) is numba until the C loop of issue 27
replaces it, and a numba loop cannot call C functions and stay cacheable.  This module keeps,
until then, exactly the functions that loop calls (``plant_io``, ``actuated_io``,
``actuated_io_held``, and ``inverse_terms`` for the exact-model controller, registered as the
numba implementation of :func:`plant.fast5r.inverse_terms`), reading the same buffers (the
C structs' layouts, which are this module's).  Delete it, and its import in plant/fast5r.py,
when fmus/adapters.py runs ``pc_fivebar_plant_io``/``pc_fivebar_actuated_io``.
``tests/test_kernels_fivebar.py`` holds it to the C kernel meanwhile.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.extending import overload

from . import fast5r

# Layout of the parameter vector.
_L0, _M0, _GX, _GY = 0, 1, 2, 3
_CHAIN = 4          # first chain offset; each chain has 9 entries
_L1, _L2, _LG1, _LG2, _M1, _M2, _JZ1, _JZ2, _JR = range(9)
_SIGN = (1.0, -1.0)  # s_k of E_k (7.3-7.4)


@njit(cache=True, fastmath=False)
def _chain_terms(p, k, a, b, da, db, out):
    """Tip, J_v, tip bias, M, v, g of chain k in world-aligned form (E_k applied).

    out[0:2] = E_k tip, out[2:6] = E_k J_v (row-major 2x2), out[6:8] = E_k a_bias,
    out[8:12] = M (2x2), out[12:14] = v, out[14:16] = g.
    """
    o = _CHAIN + 9 * k
    s = 1.0 if k == 0 else -1.0
    l1, l2 = p[o + _L1], p[o + _L2]
    lg1, lg2 = p[o + _LG1], p[o + _LG2]
    m1, m2 = p[o + _M1], p[o + _M2]
    c1, s1 = math.cos(a), math.sin(a)
    c12, s12 = math.cos(a + b), math.sin(a + b)
    cb, sb = math.cos(b), math.sin(b)
    w1 = da
    w12 = da + db
    # Tip (4.4) and J_v (4.13) in the chain frame; only x, y rows are non-zero.
    tx = l1 * c1 + l2 * c12
    ty = l1 * s1 + l2 * s12
    j11 = -l1 * s1 - l2 * s12
    j12 = -l2 * s12
    j21 = l1 * c1 + l2 * c12
    j22 = l2 * c12
    # Velocity-quadratic tip acceleration (4.57-4.58): centripetal terms.
    ax = -l1 * c1 * w1 * w1 - l2 * c12 * w12 * w12
    ay = -l1 * s1 * w1 * w1 - l2 * s12 * w12 * w12
    out[0] = s * tx
    out[1] = ty
    out[2] = s * j11
    out[3] = s * j12
    out[4] = j21
    out[5] = j22
    out[6] = s * ax
    out[7] = ay
    # (4.85) with the rotor of (4.139) on joint 1.
    h = m2 * l1 * lg2
    m22 = m2 * lg2 * lg2 + p[o + _JZ2]
    out[8] = m1 * lg1 * lg1 + p[o + _JZ1] + m2 * l1 * l1 + m22 + 2.0 * h * cb + p[o + _JR]
    out[9] = m22 + h * cb
    out[10] = out[9]
    out[11] = m22
    # (4.86): Coriolis and centripetal efforts.
    out[12] = -h * sb * (2.0 * da * db + db * db)
    out[13] = h * sb * da * da
    # (4.87) with gravity written in the chain frame, E_k^T g.
    gx = s * p[_GX]
    gy = p[_GY]
    gc1x = lg1 * -s1
    gc1y = lg1 * c1
    g2ax = -l1 * s1 - lg2 * s12
    g2ay = l1 * c1 + lg2 * c12
    g2bx = -lg2 * s12
    g2by = lg2 * c12
    out[14] = -(m1 * (gc1x * gx + gc1y * gy) + m2 * (g2ax * gx + g2ay * gy))
    out[15] = -(m2 * (g2bx * gx + g2by * gy))


@njit(cache=True)
def _inv2(m00, m01, m10, m11):
    det = m00 * m11 - m01 * m10
    return m11 / det, -m01 / det, -m10 / det, m00 / det


@njit(cache=True)
def derivative(p, y, u1, u2, lam, out):
    """out = dy/dt for y = [q(7), dq(7)] with u* = (u1, u2) on theta11, theta21 (5.66)."""
    terms = np.empty((2, 16))
    for k in range(2):
        _chain_terms(p, k, y[3 + 2 * k], y[4 + 2 * k], y[10 + 2 * k], y[11 + 2 * k], terms[k])
    x, yy = y[0], y[1]
    dx, dy = y[7], y[8]
    l0 = p[_L0]
    m0 = p[_M0]
    # Per chain: theta'' = Cinv_k (x'' - w_k), w_k from the Baumgarte rows.
    cinv = np.empty((2, 4))
    e = np.empty((2, 2))
    for k in range(2):
        t = terms[k]
        base = l0 if k == 0 else -l0
        rx = x - base - t[0]                     # residual (5.18)
        ry = yy - t[1]
        dth1 = y[10 + 2 * k]
        dth2 = y[11 + 2 * k]
        vrx = dx - (t[2] * dth1 + t[3] * dth2)   # A dq
        vry = dy - (t[4] * dth1 + t[5] * dth2)
        # A q'' + b + 2 lam A dq + lam^2 res = 0, A = [1, -E J], b = -E a_bias:
        # E J theta'' = x'' - E a_bias + 2 lam (A dq) + lam^2 res.
        wx = -t[6] + 2.0 * lam * vrx + lam * lam * rx
        wy = -t[7] + 2.0 * lam * vry + lam * lam * ry
        i00, i01, i10, i11 = _inv2(t[2], t[3], t[4], t[5])
        cinv[k, 0], cinv[k, 1], cinv[k, 2], cinv[k, 3] = i00, i01, i10, i11
        e[k, 0] = i00 * wx + i01 * wy
        e[k, 1] = i10 * wx + i11 * wy
    # Projected dynamics: (C^T M' C) x'' = C^T (u' - v' - g' - M' e).
    a00 = m0
    a01 = 0.0
    a11 = m0
    r0 = m0 * p[_GX]      # -g' of the platform (5.9)
    r1 = m0 * p[_GY]
    for k in range(2):
        t = terms[k]
        c = cinv[k]
        u = u1 if k == 0 else u2
        f0 = u - t[12] - t[14] - (t[8] * e[k, 0] + t[9] * e[k, 1])
        f1 = -t[13] - t[15] - (t[10] * e[k, 0] + t[11] * e[k, 1])
        # M C (2x2) then C^T M C
        mc00 = t[8] * c[0] + t[9] * c[2]
        mc01 = t[8] * c[1] + t[9] * c[3]
        mc10 = t[10] * c[0] + t[11] * c[2]
        mc11 = t[10] * c[1] + t[11] * c[3]
        a00 += c[0] * mc00 + c[2] * mc10
        a01 += c[0] * mc01 + c[2] * mc11
        a11 += c[1] * mc01 + c[3] * mc11
        r0 += c[0] * f0 + c[2] * f1
        r1 += c[1] * f0 + c[3] * f1
    det = a00 * a11 - a01 * a01
    ddx = (a11 * r0 - a01 * r1) / det
    ddy = (a00 * r1 - a01 * r0) / det
    for i in range(7):
        out[i] = y[7 + i]
    out[7] = ddx
    out[8] = ddy
    out[9] = -2.0 * lam * y[9] - lam * lam * y[2]
    for k in range(2):
        c = cinv[k]
        out[10 + 2 * k] = c[0] * ddx + c[1] * ddy + e[k, 0]
        out[11 + 2 * k] = c[2] * ddx + c[3] * ddy + e[k, 1]


#: Columns of one motor row of :func:`actuated_derivative`: the joint it drives (0: tau1/q1,
#: 1: tau2/q2, world convention), then R, L, kt, ke, b, mu, omega_eps (motor.MotorParams).
MOTOR_COLUMNS = 8
NO_MOTORS = np.empty((0, MOTOR_COLUMNS))
NO_VOLTAGES = np.empty(0)


@njit(cache=True)
def actuated_derivative(p, motors, y, v, u1, u2, lam, out):
    """out = dz/dt for z = [q(7), dq(7), i_1 .. i_n]: the plant (5.66) and n armature circuits.

    Motor n (row ``motors[n]``, :data:`MOTOR_COLUMNS`) on world joint j at speed omega
    (``plant.fivebar.world_rates``) delivers the shaft torque kt i - b omega - mu tanh(omega /
    omega_eps) (B.2, ``motor.shaft_torque``), added to the held efforts (u1, u2) on theta11,
    theta21 (world -> thesis sign as ``plant.fivebar.thesis_torques``), and its current obeys
    L di/dt = v_n - R i - ke omega (4.162, ``motor.armature_current_rate``).  With no motors
    this is :func:`derivative`.  ``plant.actuated.ActuatedPlant.derivative`` is the Python
    reference it is tested against.
    """
    for n in range(motors.shape[0]):
        joint = int(motors[n, 0])
        sign = 1.0 if joint == 0 else -1.0
        omega = sign * y[10 + 2 * joint]
        i = y[14 + n]
        tau = motors[n, 3] * i - motors[n, 5] * omega - motors[n, 6] * math.tanh(omega / motors[n, 7])
        if joint == 0:
            u1 += tau
        else:
            u2 -= tau
        out[14 + n] = (v[n] - motors[n, 1] * i - motors[n, 4] * omega) / motors[n, 2]
    derivative(p, y, u1, u2, lam, out)


@njit(cache=True)
def actuated_rk4(p, motors, y, v, u1, u2, lam, dt, substeps):
    """Classical RK4, ``substeps`` steps over dt, of :func:`actuated_derivative` (inputs held;
    the same scheme as plant.integrators.rk4)."""
    h = dt / substeps
    n = y.size
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    tmp = np.empty(n)
    y = y.copy()
    for _ in range(substeps):
        actuated_derivative(p, motors, y, v, u1, u2, lam, k1)
        for i in range(n):
            tmp[i] = y[i] + 0.5 * h * k1[i]
        actuated_derivative(p, motors, tmp, v, u1, u2, lam, k2)
        for i in range(n):
            tmp[i] = y[i] + 0.5 * h * k2[i]
        actuated_derivative(p, motors, tmp, v, u1, u2, lam, k3)
        for i in range(n):
            tmp[i] = y[i] + h * k3[i]
        actuated_derivative(p, motors, tmp, v, u1, u2, lam, k4)
        for i in range(n):
            y[i] += (h / 6.0) * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    return y


#: Layout of the report of :func:`actuated_step`: 1.0 if every state is finite; the norm of
#: the position residual (5.18); the three singularity measures of
#: ``plant.simulator.PlantSimulator`` (sin theta12, sin theta22, sin(phi12 - phi22)); then the
#: plant's outputs q1, q2, dq1, dq2, x, y, dx, dy, q1_enc, q2_enc (world convention,
#: ``plant.fivebar.world_angles``/``world_rates``; encoder k reads q_k + its zero error
#: ``offset<k>``, quantised to ``count``: ``PlantSimulator.encoder_offsets``).
REPORT_FINITE, REPORT_RESIDUAL, REPORT_MEASURES, REPORT_OUTPUTS, REPORT_SIZE = 0, 1, 2, 5, 15


@njit(cache=True)
def report(p, y, count, offset1, offset2, out):
    """What the simulator checks and publishes after a step, for the state y (layout above)."""
    finite = True
    for i in range(y.size):
        if not math.isfinite(y[i]):
            finite = False
    out[REPORT_FINITE] = 1.0 if finite else 0.0
    res = np.empty(6)
    residual(p, y, res)
    out[REPORT_RESIDUAL] = math.sqrt(np.dot(res, res))
    out[REPORT_MEASURES] = math.sin(y[4])
    out[REPORT_MEASURES + 1] = math.sin(y[6])
    out[REPORT_MEASURES + 2] = math.sin((y[3] + y[4]) - (math.pi - (y[5] + y[6])))
    q1, q2 = y[3], math.pi - y[5]
    o = REPORT_OUTPUTS
    out[o], out[o + 1], out[o + 2], out[o + 3] = q1, q2, y[10], -y[12]
    out[o + 4], out[o + 5], out[o + 6], out[o + 7] = y[0], y[1], y[7], y[8]
    out[o + 8] = count * math.floor((q1 + offset1) / count + 0.5)
    out[o + 9] = count * math.floor((q2 + offset2) / count + 0.5)


@njit(cache=True)
def actuated_step(p, motors, y, v, u1, u2, lam, dt, substeps, count, offset1, offset2, out):
    """:func:`actuated_rk4`, then :func:`report` of the new plant state into ``out``; returns z."""
    z = actuated_rk4(p, motors, y, v, u1, u2, lam, dt, substeps)
    report(p, z[:14], count, offset1, offset2, out)
    return z


@njit(cache=True)
def residual(p, y, out):
    """The position constraint residual q̄ (5.18, 7.7), 6 entries."""
    t = np.empty(16)
    l0 = p[_L0]
    for k in range(2):
        base = l0 if k == 0 else -l0
        _chain_terms(p, k, y[3 + 2 * k], y[4 + 2 * k], 0.0, 0.0, t)
        out[3 * k] = y[0] - base - t[0]
        out[3 * k + 1] = y[1] - t[1]
        out[3 * k + 2] = y[2]


#: Layout of :func:`inverse_terms`' output: M_M (2x2, row-major), v_M, g_M, Z (2x2, row-major), c (7).
INVERSE_M, INVERSE_V, INVERSE_G, INVERSE_Z, INVERSE_C, INVERSE_SIZE = 0, 4, 6, 8, 12, 19


@njit(cache=True)
def inverse_terms_jit(p, q, dq, out):
    """The inverse dynamics terms of (5.67-5.77) at (q, dq), as :func:`plant.parallel.inverse_dynamics_terms`.

    ``M_M ddq# + v_M + g_M = Z^T u*`` (5.74) with q# = (x, y).  Same elimination as
    :func:`derivative`: the chain blocks of C (5.56) are Cinv_k = (E_k J_v,k)^-1, so

    * ``M_M = m0 1 + sum_k Cinv_k^T M_k Cinv_k`` (5.75);
    * c (5.69): the chains' accelerations at ddq# = 0, ``c_k = -Cinv_k E_k a_bias,k``
      (platform rows 0), and ``v_M = sum_k Cinv_k^T (M_k c_k + v_k)`` (5.76);
    * ``g_M = -m0 g_xy + sum_k Cinv_k^T g_k`` (5.77, 5.9);
    * ``Z = U^T C``: the rows of C of theta11 and theta21 (5.72).

    ``out`` (:data:`INVERSE_SIZE` entries): out[0:4] M_M, out[4:6] v_M, out[6:8] g_M,
    out[8:12] Z, out[12:19] c.
    """
    t = np.empty(16)
    m0 = p[_M0]
    m00 = m0
    m01 = 0.0
    m11 = m0
    v0 = 0.0
    v1 = 0.0
    g0 = -m0 * p[_GX]
    g1 = -m0 * p[_GY]
    for i in range(7):
        out[INVERSE_C + i] = 0.0
    for k in range(2):
        _chain_terms(p, k, q[3 + 2 * k], q[4 + 2 * k], dq[3 + 2 * k], dq[4 + 2 * k], t)
        i00, i01, i10, i11 = _inv2(t[2], t[3], t[4], t[5])
        c0 = i00 * -t[6] + i01 * -t[7]
        c1 = i10 * -t[6] + i11 * -t[7]
        out[INVERSE_C + 3 + 2 * k] = c0
        out[INVERSE_C + 4 + 2 * k] = c1
        # M_k Cinv_k, then Cinv_k^T (M_k Cinv_k)
        mc00 = t[8] * i00 + t[9] * i10
        mc01 = t[8] * i01 + t[9] * i11
        mc10 = t[10] * i00 + t[11] * i10
        mc11 = t[10] * i01 + t[11] * i11
        m00 += i00 * mc00 + i10 * mc10
        m01 += i00 * mc01 + i10 * mc11
        m11 += i01 * mc01 + i11 * mc11
        f0 = t[8] * c0 + t[9] * c1 + t[12]
        f1 = t[10] * c0 + t[11] * c1 + t[13]
        v0 += i00 * f0 + i10 * f1
        v1 += i01 * f0 + i11 * f1
        g0 += i00 * t[14] + i10 * t[15]
        g1 += i01 * t[14] + i11 * t[15]
        out[INVERSE_Z + 2 * k] = i00
        out[INVERSE_Z + 2 * k + 1] = i01
    out[INVERSE_M] = m00
    out[INVERSE_M + 1] = m01
    out[INVERSE_M + 2] = m01
    out[INVERSE_M + 3] = m11
    out[INVERSE_V] = v0
    out[INVERSE_V + 1] = v1
    out[INVERSE_G] = g0
    out[INVERSE_G + 1] = g1


# --- the compiled scene's calls (fmus.compiled) ------------------------------------------------
#: Status codes of :func:`plant_io` and :func:`actuated_io`; on a refusal the state is unchanged.
OK, NONFINITE_INPUT, NONFINITE_STATE, DIVERGED, SINGULAR = 0, 1, 2, 3, 4
#: Layout of the settings array of :func:`plant_io`: Baumgarte lambda, RK4 steps per step,
#: one encoder count [rad], the largest residual and the smallest singularity measure accepted
#: (plant.simulator.RESIDUAL_STOP, SINGULAR_STOP), the two encoders' zero errors [rad]
#: (PlantSimulator.encoder_offsets).
S_LAMBDA, S_SUBSTEPS, S_COUNT, S_RESIDUAL_STOP, S_SINGULAR_STOP, S_OFFSET1, S_OFFSET2, SETTINGS_SIZE = range(8)
#: Entries of x after the inputs: the FiveBarPlant outputs (fmus.parts.PLANT_OUTPUTS order).
PLANT_OUTPUT_COUNT = 11


@njit(cache=True)
def _accept(s, out):
    """The status of a step whose :func:`report` is ``out`` (PlantSimulator.accept's checks)."""
    if out[REPORT_FINITE] != 1.0:
        return NONFINITE_STATE
    if not out[REPORT_RESIDUAL] <= s[S_RESIDUAL_STOP]:
        return DIVERGED
    for k in range(3):
        if abs(out[REPORT_MEASURES + k]) < s[S_SINGULAR_STOP]:
            return SINGULAR
    return OK


@njit(cache=True)
def _publish(out, x, first):
    """The plant's outputs from the report ``out`` into x[first:first + 11]."""
    for k in range(10):
        x[first + k] = out[REPORT_OUTPUTS + k]
    x[first + 10] = out[REPORT_RESIDUAL]


@njit(cache=True)
def plant_io(p, y, s, x, dt):
    """FiveBarPlant with RK4, no projection: x = [tau1, tau2 | the 11 plant outputs].

    The state y (14) is replaced by the new one only when the step is accepted.
    """
    tau1, tau2 = x[0], x[1]
    if not (math.isfinite(tau1) and math.isfinite(tau2)):
        return NONFINITE_INPUT
    out = np.empty(REPORT_SIZE)
    z = actuated_step(p, NO_MOTORS, y, NO_VOLTAGES, tau1, -tau2, s[S_LAMBDA], dt, int(s[S_SUBSTEPS]),
                      s[S_COUNT], s[S_OFFSET1], s[S_OFFSET2], out)
    status = _accept(s, out)
    if status == OK:
        y[:] = z
        _publish(out, x, 2)
    return status


@njit(cache=True)
def actuated_io(p, s, motors, z, voltages, x, first, dt):
    """ActuatedFiveBarPlant's integration with the drives' ``voltages`` held: z = [q, dq, currents].

    On acceptance z is replaced and x[first:first + 11] gets the plant's outputs;
    x[first + 11 + n] the shaft torque of motor n at the new current and joint speed (B.2).
    Refused, nothing changed: a non-finite state or current, divergence, a singular pose.
    """
    return actuated_io_held(p, s, motors, z, voltages, x, first, dt, 0.0, 0.0)


@njit(cache=True)
def actuated_io_held(p, s, motors, z, voltages, x, first, dt, u1, u2):
    """:func:`actuated_io` with efforts (u1, u2) on theta11, theta21 held besides the motors'
    (the drives' LuGre bristle torques, ``plant.actuated.ActuatedPlant.held_friction``)."""
    out = np.empty(REPORT_SIZE)
    w = actuated_step(p, motors, z, voltages, u1, u2, s[S_LAMBDA], dt, int(s[S_SUBSTEPS]), s[S_COUNT],
                      s[S_OFFSET1], s[S_OFFSET2], out)
    for n in range(motors.shape[0]):
        if not math.isfinite(w[14 + n]):
            return NONFINITE_STATE
    status = _accept(s, out)
    if status == OK:
        z[:] = w
        _publish(out, x, first)
        for n in range(motors.shape[0]):
            joint = int(motors[n, 0])
            omega = w[10] if joint == 0 else -w[12]
            x[first + 11 + n] = (motors[n, 3] * w[14 + n] - motors[n, 5] * omega
                                 - motors[n, 6] * math.tanh(omega / motors[n, 7]))
    return status


@overload(fast5r.inverse_terms, jit_options={"cache": True})
def _inverse_terms_in_numba(p, q, dq, out):
    """:func:`plant.fast5r.inverse_terms` inside the numba loop."""
    return lambda p, q, dq, out: inverse_terms_jit(p, q, dq, out)
