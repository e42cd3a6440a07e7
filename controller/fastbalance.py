"""The wheeled pendulum's balance controller sample compiled with numba (one kernel, named layout).

:class:`controller.balance.BalanceController` (in process, the FMU) and the compiled loop
(:mod:`fmus.adapters`) all call :func:`balance_io`: correct the observer's estimate with the
encoders and the gyro, u = -K (x_hat - x_ref(t)) saturated at +-v_battery, predict the next
estimate with the voltage applied (controller/balance.py's module docstring).  The design
(python-control) stays in Python; :func:`pack` copies its matrices into ``buf``.

Layout of ``buf`` (float64): the scalars ``B_*``, the route's window and the smooth step
(7.27)'s coefficients, the kept state indices, the estimate ``x_hat`` and the matrices,
each at its maximal size (6 states, 3 measurements, 2 voltages), row-major.  Layout of the
I/O array ``x``: :data:`INPUTS` then :data:`OUTPUTS`.

Refusals: an input that is non-finite or beyond ``limit`` makes :func:`balance_io` return
:data:`REFUSED` without touching ``buf``; the caller's Python path raises the message.
The module calls no compiled function of another file (numba's cache watches this file only).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

INPUTS = ("enc_l", "enc_r", "gyro")
OUTPUTS = ("v_l", "v_r", "tau_l", "tau_r", "x_d", "y_d",
           "theta_hat", "psi_hat", "phi_hat", "dtheta_hat", "dpsi_hat", "dphi_hat")
I_ENC_L, I_ENC_R, I_GYRO = 0, 1, 2
O_V, O_TAU, O_REF, O_HAT = 3, 5, 7, 9
IO_SIZE = len(INPUTS) + len(OUTPUTS)

N_MAX, NY_MAX = 6, 3
# --- layout of buf ---------------------------------------------------------------------
B_N, B_NY, B_YAW = 0, 1, 2                 # kept states, measurements, yaw controlled (1/0)
B_R_OVER_W = 3                             # R/W: yaw from the encoders
B_RADIUS = 4                               # wheel radius R [m] (theta_d = distance s / R)
B_V_MAX, B_GAIN = 5, 6                     # v_battery [V], K_t/R_m [N m/V]
B_STARTED = 7                              # 1 once x_hat holds an estimate
B_DISTANCE, B_TURN = 8, 9                  # route (controller.balance.Route)
B_DRIVE, B_TURNING = 10, 12                # (start, end) windows [s]
B_SMOOTH = 14                              # 8 coefficients of s(tau), (7.27), ascending
B_SLOPE = 22                               # 7 coefficients of s'(tau), ascending
B_STATES = 29                              # kept state indices (N_MAX, -1 unused)
B_X_HAT = B_STATES + N_MAX                 # the estimate (N_MAX)
B_U = B_X_HAT + N_MAX                      # the last voltages (2)
B_K = B_U + 2                              # K (2 x N_MAX)
B_LO = B_K + 2 * N_MAX                     # Lo (N_MAX x NY_MAX)
B_C = B_LO + N_MAX * NY_MAX                # C (NY_MAX x N_MAX)
B_AD = B_C + NY_MAX * N_MAX                # Ad (N_MAX x N_MAX)
B_BD = B_AD + N_MAX * N_MAX                # Bd (N_MAX x 2)
BUF_SIZE = B_BD + N_MAX * 2
#: The words of the buffer a run changes (started, the estimate, the last voltages); every
#: other word is configuration (sizes, kept-state indices the kernel indexes with, gains,
#: matrices), which a restored FMU state may not change (:mod:`fmus.fmustate`).
RUN_STATE_WORDS = (B_STARTED,) + tuple(range(B_X_HAT, B_X_HAT + N_MAX)) + (B_U, B_U + 1)


def run_state_words(buf):
    """The indices of ``buf`` a run changes (:data:`RUN_STATE_WORDS`)."""
    return RUN_STATE_WORDS

OK, REFUSED = 0, 1


def pack(design, route, R: float, W: float, torque_per_volt: float, smooth, slope) -> np.ndarray:
    """The ``buf`` of :func:`balance_io` for a :class:`controller.balance.BalanceDesign`, a
    :class:`controller.balance.Route` and the smooth step's coefficients (ascending)."""
    n, ny = len(design.states), design.C.shape[0]
    buf = np.zeros(BUF_SIZE)
    buf[B_N], buf[B_NY], buf[B_YAW] = n, ny, 1.0 if design.settings.yaw else 0.0
    buf[B_R_OVER_W], buf[B_RADIUS] = R / W, R
    buf[B_V_MAX], buf[B_GAIN] = design.settings.v_battery, torque_per_volt
    buf[B_DISTANCE], buf[B_TURN] = route.distance, route.turn
    buf[B_DRIVE:B_DRIVE + 2], buf[B_TURNING:B_TURNING + 2] = route.drive, route.turning
    buf[B_SMOOTH:B_SMOOTH + 8], buf[B_SLOPE:B_SLOPE + 7] = smooth, slope
    buf[B_STATES:B_STATES + N_MAX] = -1.0
    buf[B_STATES:B_STATES + n] = design.states
    for first, matrix, cols in ((B_K, design.K, N_MAX), (B_LO, design.Lo, NY_MAX), (B_C, design.C, N_MAX),
                                (B_AD, design.Ad, N_MAX), (B_BD, design.Bd, 2)):
        rows, width = matrix.shape
        for i in range(rows):
            buf[first + i * cols:first + i * cols + width] = matrix[i]
    return buf


@njit(cache=True)
def _smooth(buf, t, first):
    """(s, s') of (7.27) over the window buf[first:first + 2] at t (Horner, as
    :func:`controller.trajectories.smoothstep`)."""
    start, end = buf[first], buf[first + 1]
    if t <= start:
        return 0.0, 0.0
    if t >= end:
        return 1.0, 0.0
    tau = (t - start) / (end - start)
    value = 0.0
    for i in range(7, -1, -1):
        value = value * tau + buf[B_SMOOTH + i]
    slope = 0.0
    for i in range(6, -1, -1):
        slope = slope * tau + buf[B_SLOPE + i]
    return value, slope / (end - start)


@njit(cache=True)
def balance_io(buf, x, t, limit):
    """One sample at time t: inputs from ``x`` (layout :data:`INPUTS`), outputs into it.

    Returns :data:`OK`, or :data:`REFUSED` (nothing changed) for an input that is not finite
    or beyond ``limit``.
    """
    for i in range(3):
        if not abs(x[i]) <= limit:
            return REFUSED
    enc_l, enc_r, gyro = x[I_ENC_L], x[I_ENC_R], x[I_GYRO]
    n, ny = int(buf[B_N]), int(buf[B_NY])
    y = np.empty(NY_MAX)
    y[0] = 0.5 * (enc_l + enc_r)
    y[1] = gyro
    y[2] = buf[B_R_OVER_W] * (enc_r - enc_l) if buf[B_YAW] != 0.0 else 0.0
    xh = buf[B_X_HAT:B_X_HAT + N_MAX]
    if buf[B_STARTED] == 0.0:   # start: theta - psi from the encoders, at rest, psi unknown (0)
        full = np.array([y[0], 0.0, y[2], 0.0, gyro, 0.0])
        for i in range(n):
            xh[i] = full[int(buf[B_STATES + i])]
        buf[B_STARTED] = 1.0
    innovation = np.empty(NY_MAX)
    for r in range(ny):
        acc = 0.0
        for j in range(n):
            acc += buf[B_C + r * N_MAX + j] * xh[j]
        innovation[r] = y[r] - acc
    for i in range(n):
        acc = 0.0
        for r in range(ny):
            acc += buf[B_LO + i * NY_MAX + r] * innovation[r]
        xh[i] = xh[i] + acc
    s, ds = _smooth(buf, t, B_DRIVE)
    a, da = _smooth(buf, t, B_TURNING)
    R = buf[B_RADIUS]
    full_ref = np.array([buf[B_DISTANCE] * s / R, 0.0, buf[B_TURN] * a, buf[B_DISTANCE] * ds / R, 0.0,
                         buf[B_TURN] * da])
    v_max = buf[B_V_MAX]
    for k in range(2):
        acc = 0.0
        for j in range(n):
            acc += buf[B_K + k * N_MAX + j] * (xh[j] - full_ref[int(buf[B_STATES + j])])
        buf[B_U + k] = min(max(-acc, -v_max), v_max)
    predicted = np.empty(N_MAX)
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += buf[B_AD + i * N_MAX + j] * xh[j]
        predicted[i] = acc + (buf[B_BD + 2 * i] * buf[B_U] + buf[B_BD + 2 * i + 1] * buf[B_U + 1])
    for i in range(n):
        xh[i] = predicted[i]
    gain = buf[B_GAIN]
    x[O_V], x[O_V + 1] = buf[B_U], buf[B_U + 1]
    x[O_TAU], x[O_TAU + 1] = gain * buf[B_U], gain * buf[B_U + 1]
    x[O_REF], x[O_REF + 1] = buf[B_DISTANCE] * s, 0.0
    for i in range(N_MAX):
        x[O_HAT + i] = 0.0
    for i in range(n):
        x[O_HAT + int(buf[B_STATES + i])] = xh[i]
    return OK
