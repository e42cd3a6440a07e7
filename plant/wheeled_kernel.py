"""The binding of the wheeled pendulum's C kernel (``kernels/src/wheeled.c``, equations in
``wheeled.h``): its layouts, refusal codes and functions, through ctypes.

Buffers are numpy float64 arrays laid out as the C structs (:func:`kernels.layout`): the
parameters (:data:`PARAMS`, ``pc_wheeled_params``), the state (:data:`STATE`, indices
:data:`THETA` ... :data:`DPHI`) and the compiled loop's settings (:data:`SETTINGS`).
"""
from __future__ import annotations

import ctypes

import numpy as np

import kernels

_vp, _d, _i = ctypes.c_void_p, ctypes.c_double, ctypes.c_int

#: Field -> slice of the parameter buffer (seed 000's symbols; ``nonholonomic`` 1.0 for the
#: exact model, 0.0 for the seed's; ``yaw`` 0.0 locks the yaw).
PARAMS = kernels.layout("pc_wheeled_params_fields")
PARAMS_SIZE = kernels.size(PARAMS)
#: Field -> slice of the state buffer.
STATE = kernels.layout("pc_wheeled_state_fields")
STATE_NAMES = tuple(sorted(STATE, key=lambda name: STATE[name].start))
N_STATE = len(STATE_NAMES)
THETA, PSI, PHI, X, Y, DTHETA, DPSI, DPHI = (STATE[name].start for name in
                                             ("theta", "psi", "phi", "x", "y", "dtheta", "dpsi", "dphi"))
#: The compiled loop's settings (``pc_wheeled_settings``): RK4 substeps, encoder count [rad],
#: push torque [N m], push start and duration [s], input limit.
SETTINGS = kernels.layout("pc_wheeled_settings_fields")
SETTINGS_SIZE = kernels.size(SETTINGS)
S_SUBSTEPS, S_COUNT, S_PUSH_TORQUE, S_PUSH_START, S_PUSH_DURATION, S_LIMIT = (
    SETTINGS[name].start for name in ("substeps", "count", "push_torque", "push_start", "push_duration", "limit"))
MAX_SUBSTEPS = _i.in_dll(kernels.library(), "pc_wheeled_max_substeps").value

#: wheeled.h's refusal codes: the pitch passed +-90 degrees; a corner of the body reached the
#: floor; the state became non-finite; an input not finite; a step size not finite and > 0;
#: an input beyond the compiled loop's limit; a substep count or encoder count out of range.
OK, FALLEN_PITCH, FALLEN_FLOOR, NONFINITE, BAD_INPUT, BAD_STEP, INPUT_LIMIT, BAD_SETTING = range(8)
FALLS = (FALLEN_PITCH, FALLEN_FLOOR, NONFINITE)
INPUT_NAMES = ("tau_l", "tau_r", "tau_d")
#: The sensors and outputs of :func:`sensors`, in order (the ``WheeledPendulum`` FMU's outputs).
OUTPUT_NAMES = ("theta", "psi", "phi", "dtheta", "dpsi", "dphi", "x", "y", "omega_l", "omega_r", "enc_l", "enc_r",
                "gyro", "energy")

# The ctypes functions on addresses (the c_* ones are the per-step callers' fast path).
_derivative = kernels.function("pc_wheeled_derivative", None, _vp, _vp, _d, _d, _d, _vp)
_condition = kernels.function("pc_wheeled_condition", _i, _vp, _vp, _vp)
c_step = kernels.function("pc_wheeled_step", _i, _vp, _vp, _d, _d, _d, _d, _i, _vp, _vp)
c_energy = kernels.function("pc_wheeled_energy", _d, _vp, _vp)
c_sensors = kernels.function("pc_wheeled_sensors", None, _vp, _vp, _d, _vp)
_step_io = kernels.function("pc_wheeled_step_io", _i, _vp, _vp, _vp, _vp, _d, _d, _vp)


class Calls:
    """A pendulum's C calls on its parameter and state buffers (:func:`kernels.bind`), with the
    refusal record, the substep count taken and the sensors' output array they fill.  Kept
    outside the pendulum by :func:`calls` (:func:`kernels.owned`)."""

    __slots__ = ("refusal", "taken", "out", "step", "energy", "sensors")

    def __init__(self, prm: np.ndarray, y: np.ndarray):
        P = kernels.PER_CALL
        self.refusal, self.taken, self.out = kernels.Refusal(), _i(), np.zeros(len(OUTPUT_NAMES))
        #: step(tau_l, tau_r, tau_d, dt, substeps) -> code
        self.step = kernels.bind(c_step, prm, y, P, P, P, P, P, ctypes.addressof(self.taken), self.refusal)
        self.energy = kernels.bind(c_energy, prm, y)
        #: sensors(count): the outputs into ``out``
        self.sensors = kernels.bind(c_sensors, prm, y, P, self.out)


def calls(owner) -> Calls:
    """The :class:`Calls` on ``owner.prm`` and ``owner.y`` (a :class:`plant.wheeled.WheeledPendulum`)."""
    return kernels.owned(owner, (owner.prm, owner.y), Calls)


def new_params() -> np.ndarray:
    """A zeroed parameter buffer."""
    return np.zeros(PARAMS_SIZE)


def new_settings(**values) -> np.ndarray:
    """A settings buffer of the compiled loop (``pc_wheeled_settings``) with every field given by name."""
    missing = set(SETTINGS) - set(values)
    if missing or set(values) - set(SETTINGS):
        raise ValueError(f"the pendulum's settings are {', '.join(SETTINGS)}: missing {sorted(missing)}, "
                         f"unknown {sorted(set(values) - set(SETTINGS))}")
    settings = np.empty(SETTINGS_SIZE)
    for name, value in values.items():
        settings[SETTINGS[name]] = value
    return settings


class Context(ctypes.Structure):
    """``pc_wheeled_context``: the addresses of the parameter, state and settings buffers
    (``pc_wheeled_io``'s ``context`` in the compiled loop)."""

    _fields_ = [("params", _vp), ("state", _vp), ("settings", _vp)]


def derivative(prm: np.ndarray, y: np.ndarray, tau_l: float, tau_r: float, tau_d: float, out: np.ndarray) -> None:
    """out = dy/dt at the state y, wheel torques tau_l, tau_r and body torque tau_d [N m] held."""
    y = np.ascontiguousarray(y, dtype=float)
    _check(prm, PARAMS_SIZE, y, N_STATE, out, N_STATE)
    _derivative(kernels.address(prm), kernels.address(y), tau_l, tau_r, tau_d, kernels.address(out))


def condition(prm: np.ndarray, y: np.ndarray, refusal: kernels.Refusal | None = None) -> int:
    """OK, or the code of why the state ``y`` is no longer a standing robot (and, in
    ``refusal``, which state entry and its value)."""
    _check(prm, PARAMS_SIZE, y, N_STATE)
    return _condition(kernels.address(prm), kernels.address(y), None if refusal is None else ctypes.addressof(refusal))


def energy(prm: np.ndarray, y: np.ndarray) -> float:
    """T + U [J] of seed 000 (8), (11), (12), the floor at z = 0."""
    _check(prm, PARAMS_SIZE, y, N_STATE)
    return c_energy(kernels.address(prm), kernels.address(y))


def sensors(prm: np.ndarray, y: np.ndarray, count: float, out: np.ndarray) -> None:
    """out[:14] = :data:`OUTPUT_NAMES` of the state y; the encoders quantised to ``count`` [rad]."""
    _check(prm, PARAMS_SIZE, y, N_STATE, out, len(OUTPUT_NAMES))
    c_sensors(kernels.address(prm), kernels.address(y), count, kernels.address(out))


def step_io(prm: np.ndarray, y: np.ndarray, settings: np.ndarray, x: np.ndarray, t: float, h: float,
            refusal: kernels.Refusal) -> int:
    """``pc_wheeled_step_io``: one communication step of the compiled loop's I/O array ``x``
    (:data:`INPUT_NAMES` then :data:`OUTPUT_NAMES`); PC_OK or a code, ``refusal`` filled."""
    _check(prm, PARAMS_SIZE, y, N_STATE, settings, SETTINGS_SIZE, x, len(INPUT_NAMES) + len(OUTPUT_NAMES))
    return _step_io(kernels.address(prm), kernels.address(y), kernels.address(settings), kernels.address(x), t, h,
                    ctypes.addressof(refusal))


def _check(*pairs) -> None:
    """Each (array, size): a float64 array of at least ``size`` words (the C reads that many)."""
    for array, size in zip(pairs[::2], pairs[1::2]):
        if not (isinstance(array, np.ndarray) and array.dtype == np.float64 and array.size >= size):
            raise ValueError(f"a wheeled-pendulum kernel buffer must be a float64 array of >= {size} words")
