"""The ctypes binding of the 5R's closed-form kinematics ``kernels/src/kinematics5r.c``
(seed 002 eq. 1-20), the one copy of them: :mod:`plant.fivebar` and
:mod:`controller.kinematics` both compute through these functions.

It lives in ``plant/`` because the plant is lower in the layering than the controller.
Argument types are set once at import.
"""
from __future__ import annotations

import ctypes

import kernels

#: Results of the C functions (``PC_5R_*`` of kinematics5r.h).
OK, OUT_OF_REACH, NO_ASSEMBLY, SINGULAR = 0, 1, 2, 3

_d, _p = ctypes.c_double, ctypes.c_void_p
_D = ctypes.POINTER(ctypes.c_double)


class Geometry(ctypes.Structure):
    """``pc_5r_geometry``: the lengths, m."""

    _fields_ = [(name, ctypes.c_double) for name in ("l0", "l11", "l12", "l21", "l22")]


class Task(ctypes.Structure):
    """``pc_5r_task``: the task state of a joint measurement."""

    _fields_ = [("x", _d), ("y", _d), ("dx", _d), ("dy", _d), ("ddx", _d), ("ddy", _d), ("jx", _d * 4),
                ("jt", _d * 2), ("det", _d), ("J", _d * 4), ("beta", _d * 2), ("distance", _d)]


def geometry(params) -> Geometry:
    """The lengths of a :class:`~plant.presets.FiveBarParams` as a ``pc_5r_geometry``."""
    return Geometry(float(params.l0), float(params.chain1.l1), float(params.chain1.l2),
                    float(params.chain2.l1), float(params.chain2.l2))


_G = ctypes.POINTER(Geometry)
inverse = kernels.function("pc_5r_inverse", ctypes.c_int, _G, _d, _d, _D, _D)
margin = kernels.function("pc_5r_margin", ctypes.c_double, _D)
forward = kernels.function("pc_5r_forward", ctypes.c_int, _G, _d, _d, _D, _D, _D)
jacobians = kernels.function("pc_5r_jacobians", None, _G, _d, _d, _d, _d, _D, _D)
task_state = kernels.function("pc_5r_task_state", ctypes.c_int, _G, *([_d] * 6), ctypes.POINTER(Task))
joint_reference = kernels.function("pc_5r_joint_reference", ctypes.c_int, _G, *([_d] * 8), _D)
thesis_state = kernels.function("pc_5r_thesis_state", ctypes.c_int, _G, _d, _d, _d, _d, _D, _D, _D)
