"""Which models have a native FMU: the adapter, the kernels and the build-time data of each.

A model's ``data`` function gets the pythonfmu slave after a successful initialisation with
its start values and returns what its adapter reads as constants: ``{name: float}`` scalars
(``#define PCN_<NAME>``) and ``{name: array}`` arrays (``pcn_<name>[]``, with
``PCN_<NAME>_WORDS``).  Designs that need scipy or python-control are made here, at build
time, for the FMU's parameters (docs/native.md says which parameters are then fixed).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class NativeModel:
    """A native FMU's C parts: ``adapter`` (in fmus/native/adapters, named pcn_<model>.c:
    sources/ is flat), ``kernels`` (C files of kernels/src; their headers follow) and
    ``data`` (slave -> (scalars, arrays), module docstring); ``sampled``: sub-stepped at a
    sample time T (fmus/slave/sampling.py), with ``pcn_sampling.c`` and the kernels' counting rule."""

    adapter: str
    kernels: tuple
    data: Callable = field(default=lambda slave: ({}, {}))
    sampled: bool = False


def _derivator(slave):
    buf = slave.derivator.__class__(slave.fc_vel, slave.fc_acc, slave.T)
    buf.start_at_first_sample(2)
    n = int(buf.buf[0])
    return ({"derivator_states": n, "design_fc_vel": float(slave.fc_vel), "design_fc_acc": float(slave.fc_acc),
             "design_t": float(slave.T)},
            {"design_buffer": np.asarray(buf.buf, dtype=np.float64)})


def _trajectory(slave):
    from controller.trajectories import TRAJECTORY_KINDS, from_parameters

    used = {"side_time": slave.side_time, "frequency": slave.frequency, "x_hold": slave.x_hold,
            "y_hold": slave.y_hold}
    scalars = {"built_cycles": int(slave.cycles), **{f"built_{k}": float(v) for k, v in used.items()}}
    arrays = {}
    for kind in TRAJECTORY_KINDS:
        trajectory = from_parameters(kind, slave.cycles, **used)
        arrays[f"buffer_{kind}"] = trajectory.buf
        scalars[f"start_x_{kind}"], scalars[f"start_y_{kind}"] = (float(v) for v in trajectory.start_point)
    return scalars, arrays


def _motor_presets(fields=("R", "L", "ke")):
    """Every motor preset by name, and each field's values in that order (arrays ``preset_<field>``)."""
    from motor.presets import MOTOR_PRESETS

    names = sorted(MOTOR_PRESETS)
    return {"preset_names": names,
            **{f"preset_{f}": np.array([getattr(MOTOR_PRESETS[n], f) for n in names]) for f in fields}}


def _observer(slave):
    return {}, _motor_presets()


def _balance(slave):
    from controller.balance import ROUTES, BalanceController, get_route

    design = slave.controller.design
    scalars = {"built_t": float(slave.T), "built_v_battery": float(slave.v_battery),
               "built_friction": int(bool(slave.friction)), "built_yaw": int(bool(slave.yaw)),
               "built_encoder_counts": int(slave.encoder_counts)}
    arrays = {"built_electrics": [str(slave.electrics)]}
    for route in ROUTES:
        arrays[f"buffer_{route}"] = BalanceController(design, get_route(route)).buf
    return scalars, arrays


#: Model name -> its native parts; one line a model.
NATIVE = {
    "Derivator": NativeModel("pcn_derivator.c", ("derivator.c",), _derivator, sampled=True),
    "Trajectory": NativeModel("pcn_trajectory.c", ("trajectory.c",), _trajectory),
    "WheeledPendulum": NativeModel("pcn_wheeledpendulum.c", ("wheeled.c",)),
    "BalanceController": NativeModel("pcn_balancecontroller.c", ("balance.c",), _balance, sampled=True),
    "CurrentObserver": NativeModel("pcn_currentobserver.c", ("observer.c", "electrics.c"), _observer, sampled=True),
}
