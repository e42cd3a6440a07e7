"""The binding of the balance controller's C sample (``kernels/src/balance.c``, equations in
``balance.h``): the buffer's layout, the I/O layout, the refusal codes and :func:`sample`.

:class:`controller.balance.BalanceController` (in process, the FMU) and the compiled loop
(:mod:`fmus.cosim.compiled_adapters`) all run ``pc_balance_sample``: correct the observer's estimate with
the encoders and the gyro, u = -K (x_hat - x_ref(t)) saturated at +-v_battery, predict the
next estimate with the voltage applied (controller/balance.py's module docstring).  The
design (python-control) stays in Python; :func:`pack` copies its matrices into ``buf``.

``buf`` is one float64 array laid out as ``pc_balance``: the configuration
(``pc_balance_params``: sizes, the route's windows and the smooth step (7.27)'s
coefficients, the kept state indices, the matrices at their largest size, row-major), then
the run state (``pc_balance_state``: started, the estimate, the last voltages).  The I/O
array ``x`` holds :data:`INPUTS` then :data:`OUTPUTS`.
"""
from __future__ import annotations

import ctypes

import numpy as np

import kernels

INPUTS = ("enc_l", "enc_r", "gyro")
OUTPUTS = ("v_l", "v_r", "tau_l", "tau_r", "x_d", "y_d",
           "theta_hat", "psi_hat", "phi_hat", "dtheta_hat", "dpsi_hat", "dphi_hat")
I_ENC_L, I_ENC_R, I_GYRO = 0, 1, 2
O_V, O_TAU, O_REF, O_HAT = 3, 5, 7, 9
IO_SIZE = len(INPUTS) + len(OUTPUTS)

N_MAX, NY_MAX = 6, 3


def _buffer_layout() -> dict:
    """Field -> slice of ``buf``: the params' fields, then the state's, at their places in ``pc_balance``."""
    parts = kernels.layout("pc_balance_fields")
    fields = {}
    for part, symbol in (("params", "pc_balance_params_fields"), ("state", "pc_balance_state_fields")):
        first = parts[part].start
        for name, place in kernels.layout(symbol).items():
            fields[name] = slice(first + place.start, first + place.stop)
    return fields


#: Field -> slice of ``buf``.
BUFFER = _buffer_layout()
BUF_SIZE = kernels.size(BUFFER)
(B_N, B_NY, B_YAW, B_R_OVER_W, B_RADIUS, B_V_MAX, B_GAIN, B_DISTANCE, B_TURN, B_DRIVE, B_TURNING, B_SMOOTH,
 B_SLOPE, B_STATES, B_K, B_LO, B_C, B_AD, B_BD, B_STARTED, B_X_HAT, B_U) = (
    BUFFER[name].start for name in ("n", "ny", "yaw", "r_over_w", "radius", "v_max", "gain", "distance", "turn",
                                    "drive", "turning", "smooth", "slope", "states", "K", "Lo", "C", "Ad", "Bd",
                                    "started", "x_hat", "u"))
_STATE = kernels.layout("pc_balance_fields")["state"]
#: The words of the buffer a run changes (``pc_balance_state``: started, the estimate, the
#: last voltages); every other word is configuration (sizes, kept-state indices, gains,
#: matrices), which a restored FMU state may not change (:mod:`fmus.slave.state`).
RUN_STATE_WORDS = tuple(range(_STATE.start, _STATE.stop))
#: The name of each word of ``buf`` (``states[2]``), for refusals.
WORD_NAMES = tuple(name if s.stop - s.start == 1 else f"{name}[{k - s.start}]"
                   for k in range(BUF_SIZE) for name, s in BUFFER.items() if s.start <= k < s.stop)


def run_state_words(buf):
    """The indices of ``buf`` a run changes (:data:`RUN_STATE_WORDS`)."""
    return RUN_STATE_WORDS


#: balance.h's codes: an input not finite, an input beyond the limit, a size or index word
#: of the buffer out of its array's range.
OK, BAD_INPUT, INPUT_LIMIT, BAD_BUFFER = range(4)

#: ``pc_balance_sample`` on addresses (the per-sample caller's fast path; :func:`sample` checks its arrays).
c_sample = kernels.function("pc_balance_sample", ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double,
                           ctypes.c_double, ctypes.c_void_p)


class Context(ctypes.Structure):
    """``pc_balance_context``: the buffer's address and the largest |input| taken
    (``pc_balance_io``'s ``context`` in the compiled loop)."""

    _fields_ = [("balance", ctypes.c_void_p), ("limit", ctypes.c_double)]


def pack(design, route, R: float, W: float, torque_per_volt: float, smooth, slope) -> np.ndarray:
    """The ``buf`` of :func:`sample` for a :class:`controller.balance.BalanceDesign`, a
    :class:`controller.balance.Route` and the smooth step's coefficients (ascending)."""
    n, ny = len(design.states), design.C.shape[0]
    buf = np.zeros(BUF_SIZE)
    buf[B_N], buf[B_NY], buf[B_YAW] = n, ny, 1.0 if design.settings.yaw else 0.0
    buf[B_R_OVER_W], buf[B_RADIUS] = R / W, R
    buf[B_V_MAX], buf[B_GAIN] = design.settings.v_battery, torque_per_volt
    buf[B_DISTANCE], buf[B_TURN] = route.distance, route.turn
    buf[BUFFER["drive"]], buf[BUFFER["turning"]] = route.drive, route.turning
    buf[BUFFER["smooth"]], buf[BUFFER["slope"]] = smooth, slope
    buf[BUFFER["states"]] = -1.0
    buf[B_STATES:B_STATES + n] = design.states
    for first, matrix, cols in ((B_K, design.K, N_MAX), (B_LO, design.Lo, NY_MAX), (B_C, design.C, N_MAX),
                                (B_AD, design.Ad, N_MAX), (B_BD, design.Bd, 2)):
        rows, width = matrix.shape
        for i in range(rows):
            buf[first + i * cols:first + i * cols + width] = matrix[i]
    return buf


def sample(buf: np.ndarray, x: np.ndarray, t: float, limit: float, refusal: kernels.Refusal) -> int:
    """``pc_balance_sample`` on ``buf`` and the I/O array ``x`` at time t: OK, or a code with
    ``refusal`` filled (nothing changed)."""
    for array, size in ((buf, BUF_SIZE), (x, IO_SIZE)):
        if not (isinstance(array, np.ndarray) and array.dtype == np.float64 and array.size >= size):
            raise ValueError(f"a balance kernel buffer must be a float64 array of >= {size} words")
    return c_sample(kernels.address(buf), kernels.address(x), t, limit, ctypes.addressof(refusal))
