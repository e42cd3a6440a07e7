"""TRANSITIONAL: the drive's voltage sample in two calls for the compiled loop's
ActuatedFiveBarPlant adapter (fmus/adapters.py), whose Python callback still calls these two
names; it goes when that adapter runs its C I/O step.  Both call kernels/src/drive.c."""
from __future__ import annotations

import ctypes

import kernels


class Sample(ctypes.Structure):
    """``pc_drive_sample``: a voltage sample not yet kept."""

    _fields_ = [("v", ctypes.c_double), ("e", ctypes.c_double), ("sampled", ctypes.c_double),
                ("phase", ctypes.c_double)]


_p, _d = ctypes.c_void_p, ctypes.c_double
_peek = kernels.function("pc_drive_peek_voltage", ctypes.c_int, _p, _p, _d, _d, _d, _d, _p, _p)
_commit = kernels.function("pc_drive_commit", None, _p, _p, _p, _d)


def peek_voltage(d, c, i_ref, v_ref, i_hat, h):
    """(status, v, e, sampled, phase) of ``pc_drive_peek_voltage``: nothing changed."""
    s = Sample()
    status = _peek(kernels.address(d), kernels.address(c), i_ref, v_ref, i_hat, h, ctypes.addressof(s), None)
    return status, s.v, s.e, s.sampled, s.phase


def commit_step(d, c, v, e, sampled, phase, i):
    """``pc_drive_commit``: keep the sample of :func:`peek_voltage` and the step's end current i."""
    sample = Sample(v, e, sampled, phase)   # alive over the call
    _commit(kernels.address(d), kernels.address(c), ctypes.addressof(sample), i)

