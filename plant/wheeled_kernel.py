"""Compiled kernel of the two-wheeled inverted pendulum (seed 000), with named layouts.

One file, one kernel family (numba caches per file).  The parameters travel as ONE record of
the structured dtype :data:`PARAMS` (fields named as in seed 000); the state is a float64
vector whose entries are named by the module constants :data:`THETA` ... :data:`DPHI`
(compile-time constants inside the kernel); the step's outcome is an integer code of
:data:`CODES` plus the substep at which it happened.

Equations (derived by Lagrange-d'Alembert in docs/pendulum.md; seed 000 numbers in brackets),
with nu = (theta, psi, phi) and s = sin psi, c = cos psi::

    M(psi) nu'' + C(psi, nu') + G(psi) = F                                  [(17)]
    M11 = (2m + M_b) R^2 + 2 J_w,  M12 = M_b R L c,  M22 = M_b L^2 + J_psi  [(18)]
    M33 = m W^2/2 + M_b L^2 s^2 + J_phi + W^2/(2 R^2) J_w                   [(18), m not M_b: typo]
    C1  = -M_b R L s psi'^2  - k M_b L R s phi'^2                           [(18) + nonholonomic]
    C2  = -M_b L^2 s c phi'^2                                               [(18), phi' not psi': typo]
    C3  = 2 M_b L^2 s c psi' phi' + k M_b L R s theta' phi'                 [(18) + nonholonomic]
    G2  = -M_b g L s                                                        [(18)]
    F   = (tau_l + tau_r, -(tau_l + tau_r) + tau_d, W/(2R) (tau_r - tau_l)) [(20)]
    x' = R theta' cos phi,  y' = R theta' sin phi                           [(2)]

k = 1 for the exact model (``nonholonomic`` = 1), 0 for the seed's (constraints substituted
into the Lagrangian before differentiating, (13)-(16)).  M_b is the body mass (the seed's M).
tau_d is a disturbance torque on the body about the axle (scene ``pendulum_push``).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Parameter record (one element of this dtype): seed 000's symbols; ``nonholonomic`` 1.0 for
#: the exact model, 0.0 for the seed's; ``yaw`` 0.0 locks the yaw (phi' = 0, phi'' = 0).
PARAMS = np.dtype([(name, np.float64) for name in (
    "g", "m", "R", "J_w", "M", "W", "D", "H", "L", "J_psi", "J_phi", "nonholonomic", "yaw")])

#: State layout: mean wheel angle from the vertical, pitch, yaw, axle midpoint, rates.
THETA, PSI, PHI, X, Y, DTHETA, DPSI, DPHI = range(8)
N_STATE = 8
STATE_NAMES = ("theta", "psi", "phi", "x", "y", "dtheta", "dpsi", "dphi")

#: Step outcomes: the step was taken; the pitch passed +-90 degrees; a corner of the body
#: reached the floor; the state became non-finite.
OK, FALLEN_PITCH, FALLEN_FLOOR, NONFINITE = 0, 1, 2, 3
CODES = {OK: "ok", FALLEN_PITCH: "pitch beyond 90 degrees", FALLEN_FLOOR: "body touching the floor",
         NONFINITE: "non-finite state"}


@njit(cache=True)
def derivative(p, y, tau_l, tau_r, tau_d, out):
    """out = dy/dt for the state y (layout above), wheel torques tau_l, tau_r [N m] (motor on
    wheel, reaction on the body) and a body torque tau_d [N m], held."""
    s = math.sin(y[PSI])
    c = math.cos(y[PSI])
    dth, dps, dph = y[DTHETA], y[DPSI], y[DPHI]
    mb, R, L = p.M, p.R, p.L
    m11 = (2.0 * p.m + mb) * R * R + 2.0 * p.J_w
    m12 = mb * R * L * c
    m22 = mb * L * L + p.J_psi
    k = p.nonholonomic
    c1 = -mb * R * L * s * dps * dps - k * mb * L * R * s * dph * dph
    c2 = -mb * L * L * s * c * dph * dph
    g2 = -mb * p.g * L * s
    f = tau_l + tau_r
    r1 = f - c1
    r2 = -f + tau_d - c2 - g2
    det = m11 * m22 - m12 * m12
    out[THETA] = dth
    out[PSI] = dps
    out[PHI] = dph
    out[X] = R * dth * math.cos(y[PHI])
    out[Y] = R * dth * math.sin(y[PHI])
    out[DTHETA] = (m22 * r1 - m12 * r2) / det
    out[DPSI] = (m11 * r2 - m12 * r1) / det
    if p.yaw != 0.0:
        m33 = 0.5 * p.m * p.W * p.W + mb * L * L * s * s + p.J_phi + p.W * p.W / (2.0 * R * R) * p.J_w
        c3 = 2.0 * mb * L * L * s * c * dps * dph + k * mb * L * R * s * dth * dph
        out[DPHI] = (p.W / (2.0 * R) * (tau_r - tau_l) - c3) / m33
    else:
        out[DPHI] = 0.0


@njit(cache=True)
def lowest_body_point(p, psi):
    """Height above the floor [m] of the body's lowest corner: a box of depth D and height H
    standing on the axle (at height R), tilted by psi."""
    return p.R + min(0.0, p.H * math.cos(psi)) - 0.5 * p.D * abs(math.sin(psi))


@njit(cache=True)
def condition(p, y):
    """OK, or the code of why the state ``y`` is no longer a standing robot."""
    for i in range(N_STATE):
        if not math.isfinite(y[i]):
            return NONFINITE
    if abs(y[PSI]) >= 0.5 * math.pi:
        return FALLEN_PITCH
    if lowest_body_point(p, y[PSI]) <= 0.0:
        return FALLEN_FLOOR
    return OK


@njit(cache=True)
def rhs(prm, y, tau_l, tau_r, tau_d, out):
    """:func:`derivative` for the parameter array ``prm`` (shape (1,)): the entry point from
    Python (a record passed from Python is compiled anew in every process, numba's cache
    misses it; measured 1.5 s)."""
    derivative(prm[0], y, tau_l, tau_r, tau_d, out)


@njit(cache=True)
def state_condition(prm, y):
    """:func:`condition` for the parameter array ``prm`` (the entry point from Python)."""
    return condition(prm[0], y)


@njit(cache=True)
def step(prm, y, tau_l, tau_r, tau_d, dt, substeps):
    """Advance y in place over dt by ``substeps`` RK4 steps, inputs held (zero-order hold).

    Returns (code, substep): :data:`OK` and ``substeps``, or the code of the first substep
    whose end state fails :func:`condition` and its 1-based index; y then holds the state at
    the START of the step (untouched).
    """
    p = prm[0]
    h = dt / substeps
    z = y.copy()
    k1 = np.empty(N_STATE)
    k2 = np.empty(N_STATE)
    k3 = np.empty(N_STATE)
    k4 = np.empty(N_STATE)
    w = np.empty(N_STATE)
    for n in range(substeps):
        derivative(p, z, tau_l, tau_r, tau_d, k1)
        for i in range(N_STATE):
            w[i] = z[i] + 0.5 * h * k1[i]
        derivative(p, w, tau_l, tau_r, tau_d, k2)
        for i in range(N_STATE):
            w[i] = z[i] + 0.5 * h * k2[i]
        derivative(p, w, tau_l, tau_r, tau_d, k3)
        for i in range(N_STATE):
            w[i] = z[i] + h * k3[i]
        derivative(p, w, tau_l, tau_r, tau_d, k4)
        for i in range(N_STATE):
            z[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        code = condition(p, z)
        if code != OK:
            return code, n + 1
    y[:] = z
    return OK, substeps


@njit(cache=True)
def energy(prm, y):
    """T + U [J] of seed 000 (8), (11), (12), with the floor at z = 0."""
    p = prm[0]
    s = math.sin(y[PSI])
    c = math.cos(y[PSI])
    dth, dps, dph = y[DTHETA], y[DPSI], y[DPHI]
    mb, R, L, W = p.M, p.R, p.L, p.W
    t1 = 0.5 * (p.m * (2.0 * R * R * dth * dth + 0.5 * W * W * dph * dph)
                + mb * (R * R * dth * dth + L * L * dps * dps + L * L * s * s * dph * dph + 2.0 * R * L * c * dth * dps))
    t2 = p.J_w * dth * dth + 0.5 * p.J_psi * dps * dps + 0.5 * (p.J_phi + W * W / (2.0 * R * R) * p.J_w) * dph * dph
    u = 2.0 * p.m * p.g * R + mb * p.g * (R + L * c)
    return t1 + t2 + u


#: The sensors and outputs of :func:`sensors`, in order (the ``WheeledPendulum`` FMU's outputs).
OUTPUT_NAMES = ("theta", "psi", "phi", "dtheta", "dpsi", "dphi", "x", "y", "omega_l", "omega_r", "enc_l", "enc_r",
                "gyro", "energy")
#: Layout of the settings array of :func:`pendulum_io`: RK4 substeps, encoder count [rad],
#: push torque [N m], push start and duration [s], input limit.
S_SUBSTEPS, S_COUNT, S_PUSH_TORQUE, S_PUSH_START, S_PUSH_DURATION, S_LIMIT = range(6)
SETTINGS_SIZE = 6
#: :func:`pendulum_io`'s code for an input that is not finite or beyond the limit.
REFUSED_INPUT = 4


@njit(cache=True)
def sensors(prm, y, count, out, first):
    """out[first:first + 14] = :data:`OUTPUT_NAMES` of the state y: the encoders read
    theta_l,r - psi (10) quantised to ``count`` [rad], the gyro psi'."""
    p = prm[0]
    half = p.W / (2.0 * p.R)
    enc_l = y[THETA] - half * y[PHI] - y[PSI]
    enc_r = y[THETA] + half * y[PHI] - y[PSI]
    out[first + 0] = y[THETA]
    out[first + 1] = y[PSI]
    out[first + 2] = y[PHI]
    out[first + 3] = y[DTHETA]
    out[first + 4] = y[DPSI]
    out[first + 5] = y[DPHI]
    out[first + 6] = y[X]
    out[first + 7] = y[Y]
    out[first + 8] = y[DTHETA] - half * y[DPHI] - y[DPSI]
    out[first + 9] = y[DTHETA] + half * y[DPHI] - y[DPSI]
    out[first + 10] = count * math.floor(enc_l / count + 0.5)
    out[first + 11] = count * math.floor(enc_r / count + 0.5)
    out[first + 12] = y[DPSI]
    out[first + 13] = energy(prm, y)


@njit(cache=True)
def pendulum_io(prm, y, settings, x, t, dt):
    """One communication step of the ``WheeledPendulum`` FMU from t over dt: torques
    (tau_l, tau_r, tau_d) from x[0:3], the push added over the steps starting in its window
    (1e-9 s: rounding of t), then :func:`step` and :func:`sensors` into x[3:17].

    Returns the code of :func:`step` (nothing changed unless :data:`OK`), or
    :data:`REFUSED_INPUT` for an input that is not finite or beyond the limit.
    """
    limit = settings[S_LIMIT]
    for i in range(3):
        if not abs(x[i]) <= limit:
            return REFUSED_INPUT
    tau_d = x[2]
    start = settings[S_PUSH_START]
    if start - 1e-9 <= t < start + settings[S_PUSH_DURATION] - 1e-9:
        tau_d += settings[S_PUSH_TORQUE]
    code, _ = step(prm, y, x[0], x[1], tau_d, dt, int(settings[S_SUBSTEPS]))
    if code != OK:
        return code
    sensors(prm, y, settings[S_COUNT], x, 3)
    return OK
