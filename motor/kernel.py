"""The motor's C kernels (kernels/src/drive.c, observer.c) through ctypes: signatures set once
at import, the buffers' layouts read from the C structs, the refusal codes and their messages.

:class:`motor.Drive`, :class:`motor.CurrentController`, :class:`motor.CurrentObserver` and
:mod:`motor.friction` call these functions on numpy float64 buffers laid out as the C structs
``pc_drive``, ``pc_controller``, ``pc_observer`` and ``pc_lugre``.
"""
from __future__ import annotations

import ctypes

import kernels
from motor import _checks

_d, _p, _u64, _int = ctypes.c_double, ctypes.c_void_p, ctypes.c_uint64, ctypes.c_int
_ref = ctypes.POINTER(kernels.Refusal)

OK = 0
#: Refusal codes of drive.h and observer.h.
NONFINITE_INPUT, UNPREPARED_STEP, DIVERGED = 1, 2, 3

#: Field -> slice of each struct (kernels.layout).
CONTROLLER = kernels.layout("pc_controller_fields")
DRIVE = kernels.layout("pc_drive_fields")
LUGRE = kernels.layout("pc_lugre_fields")
OBSERVER = kernels.layout("pc_observer_fields")


def index(fields: dict, name: str) -> int:
    """The buffer index of a one-double field."""
    return fields[name].start


def indices(fields: dict) -> dict:
    """``{field: index}`` of a struct whose fields are single doubles."""
    return {name: s.start for name, s in fields.items() if s.stop - s.start == 1}


controller_update = kernels.function("pc_controller_update", _d, _p, _d, _d)
shaft_torque = kernels.function("pc_drive_shaft_torque", _d, _d, _d, _d, _d, _d, _d)
armature_rate = kernels.function("pc_drive_armature_rate", _d, _d, _d, _d, _d, _d, _d)
splitmix64 = kernels.function("pc_splitmix64", _u64, _u64)
uniform = kernels.function("pc_drive_uniform", _d, _u64, _u64, _u64)
gaussian = kernels.function("pc_drive_gaussian", _d, _u64, _u64, _u64)
#: The sub-step counting rule of sampled components (kernels/src/pc_sampling.c).
sampling_substeps = kernels.function("pc_sampling_substeps", _d, _d, _d)
sampling_changes_period = kernels.function("pc_sampling_changes_period", _int, _d, _d, _d)
lugre_stribeck = kernels.function("pc_lugre_stribeck", _d, _p, _d)
lugre_bristle_rate = kernels.function("pc_lugre_bristle_rate", _d, _p, _d, _d)
lugre_force = kernels.function("pc_lugre_force", _d, _p, _d, _d)
lugre_steady_deflection = kernels.function("pc_lugre_steady_deflection", _d, _p, _d)
lugre_phi = kernels.function("pc_lugre_phi", None, _d, _p)
lugre_advance = kernels.function("pc_lugre_advance", None, _p, _d, _d, _d, _p)
lugre_push = kernels.function("pc_lugre_push", None, _p, _int, _d, _d, _d, _d, _int, _p)
drive_torque = kernels.function("pc_drive_torque", _d, _p, _p, _d)
drive_step_x = kernels.function("pc_drive_step_x", _int, _p, _p, _p)
drive_sample_x = kernels.function("pc_drive_sample_x", _int, _p, _p, _p)
observer_estimate_x = kernels.function("pc_observer_estimate_x", _int, _p, _p, _p)
#: The compiled loop's I/O functions (pc_io_fn).
drive_io = kernels.function("pc_drive_io", _int, _p, _p, _d, _d, _p)
observer_io = kernels.function("pc_observer_io", _int, _p, _p, _d, _d, _p)


def call(kernel_call, names, values):
    """``kernel_call(*values)``; a value ctypes does not take as a double (a string, a numpy
    0-d array) is converted, or refused by name (a non-finite one is the kernel's to refuse)."""
    try:
        return kernel_call(*values)
    except TypeError:
        for name, value in zip(names, values):
            _checks.finite(name, value)
        return kernel_call(*(float(v) for v in values))


class DriveContext(ctypes.Structure):
    """``pc_drive_context``: the buffers ``pc_drive_io`` steps (lugre NULL: B.2's tanh friction)."""

    _fields_ = [("drive", _p), ("controller", _p), ("lugre", _p)]


class ObserverContext(ctypes.Structure):
    """``pc_observer_context``."""

    _fields_ = [("observer", _p)]


class Calls:
    """The C calls on one owner's buffers (:func:`kernels.bind`) through a context struct (the
    compiled loop's) and an I/O array ``x`` (inputs and the step length, then outputs), both
    made once: a call writes the inputs into ``x`` and passes three fixed pointers.

    An owner (:class:`motor.Drive`, ...) keeps its bound methods as attributes, which FMU
    state treats as code (fmus.slave.state.opaque_tag), never as data; a copy of the owner makes
    its own (the owner's ``__getstate__`` leaves them out, ``__setstate__`` builds them).

    Parameters
    ----------
    context : DriveContext or ObserverContext
        The addresses of the owner's buffers (laid out as the C structs).
    n : int
        The length of ``x``.
    """

    __slots__ = ("context", "x", "refusal", "_step", "_sample", "_torque", "_estimate")

    def __init__(self, context, n):
        self.context = context
        self.x = (ctypes.c_double * n)()
        self.refusal = kernels.Refusal()

    @classmethod
    def drive(cls, drive, controller, lugre=None):
        """The calls of a drive's buffers (``lugre`` None: B.2's tanh friction)."""
        calls = cls(DriveContext(*(None if b is None else kernels.address(b) for b in (drive, controller, lugre))), 8)
        calls._step = kernels.bind(drive_step_x, calls.context, calls.x, calls.refusal)
        calls._sample = kernels.bind(drive_sample_x, calls.context, calls.x, calls.refusal)
        calls._torque = kernels.bind(drive_torque, drive, lugre, kernels.PER_CALL)
        return calls

    @classmethod
    def observer(cls, observer):
        """The calls of an observer's buffer."""
        calls = cls(ObserverContext(kernels.address(observer)), 4)
        calls._estimate = kernels.bind(observer_estimate_x, calls.context, calls.x, calls.refusal)
        return calls

    def drive_step(self, i_ref, v_ref, omega, i_hat, h):
        """``pc_drive_step_x``: the code; tau, v, i in ``x[5:8]``.  TypeError: an input is not a number."""
        self.x[0:5] = (i_ref, v_ref, omega, i_hat, h)
        return self._step()

    def sample_voltage(self, i_ref, v_ref, i_hat, h):
        """``pc_drive_sample_x``: the code; v in ``x[6]``."""
        x = self.x
        x[0], x[1], x[3], x[4] = i_ref, v_ref, i_hat, h
        return self._sample()

    def torque(self, omega):
        """``pc_drive_torque``: the shaft torque of the present current at speed omega."""
        return self._torque(omega)

    def observer_estimate(self, v, omega, h):
        """``pc_observer_estimate_x``: the code; i_hat in ``x[3]`` (also a non-finite one)."""
        x = self.x
        x[0], x[1], x[2] = v, omega, h
        return self._estimate()


class Controller:
    """``pc_controller_update`` on one controller buffer (:func:`kernels.bind`; see :class:`Calls`)."""

    __slots__ = ("update",)

    def __init__(self, buf):
        #: update(i_ref, i_meas) -> one sample of K(z): the voltage
        self.update = kernels.bind(controller_update, buf, kernels.PER_CALL, kernels.PER_CALL)


#: Why a drive or observer step is refused: the input's name and the message (motor._checks.finite's).
NONFINITE = kernels.Reason("nonfinite_input", ("omega", "i_ref", "v_ref", "i_hat"), "",
                           "{variable} must be a finite number, got {value!r}")
OBSERVER_NONFINITE = kernels.Reason("nonfinite_input", ("v", "omega"), "",
                                    "{variable} must be a finite number, got {value!r}")
#: The current (index 0) or the torque (1) after a step is not finite (motor.Drive adds why).
DIVERGED_REASON = kernels.Reason("diverged", ("i", "tau"), "",
                                 "armature current i = {i!r} A, shaft torque tau = {tau!r} N m after this step are "
                                 "not finite{why}")
DRIVE_REASONS = {NONFINITE_INPUT: NONFINITE, DIVERGED: DIVERGED_REASON}
#: The observer's estimate is not finite (the CurrentObserver slave's text).
OBSERVER_DIVERGED = kernels.Reason("diverged", ("i_hat",), "A",
                                   "the estimate i_hat = {value!r} A{at} is not finite (inputs v = {v!r} V, "
                                   "omega = {omega!r} rad/s)")
OBSERVER_REASONS = {NONFINITE_INPUT: OBSERVER_NONFINITE, DIVERGED: OBSERVER_DIVERGED}
