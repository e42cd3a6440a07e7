"""Which models have a native FMU: the adapter, the kernels and the build-time data of each.

A model's ``data`` function gets the pythonfmu slave after a successful initialisation with
its start values and returns what its adapter reads as constants: ``{name: float}`` scalars
(``#define PCN_<NAME>``) and ``{name: array}`` arrays (``pcn_<name>[]``, with
``PCN_<NAME>_WORDS``).  Designs that need scipy or python-control are made here, at build
time, for the FMU's parameters (docs/native.md says which parameters are then fixed); the
designs made in C at set-up need only their presets' data here.
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
    sample time T (fmus/slave/sampling.py), with ``pcn_sampling.c`` and the kernels' counting rule;
    ``parts``: more files of fmus/native/adapters it compiles (``pcn_drive_setup.c|h``)."""

    adapter: str
    kernels: tuple
    data: Callable = field(default=lambda slave: ({}, {}))
    sampled: bool = False
    parts: tuple = ()


def _derivator(slave):
    buf = slave.derivator.__class__(slave.fc_vel, slave.fc_acc, slave.T)
    buf.start_at_first_sample(2)
    n = int(buf.buf[0])
    return ({"derivator_states": n, "design_fc_vel": float(slave.fc_vel), "design_fc_acc": float(slave.fc_acc),
             "design_t": float(slave.T)},
            {"design_buffer": np.asarray(buf.buf, dtype=np.float64)})


def _trajectory(slave):
    from controller.trajectories import TRAJECTORY_KINDS, from_parameters, parameters_of

    values = parameters_of(slave)
    scalars = {"built_cycles": int(slave.cycles),
               **{f"built_{k}": float(v) for k, v in values.items() if k not in ("kind", "cycles")}}
    arrays = {}
    for kind in TRAJECTORY_KINDS:
        trajectory = from_parameters(**{**values, "kind": kind})
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


#: plant.presets.ChainParams' fields as pcn_plant_setup.c reads a preset's chain (9 words).
PLANT_CHAIN_FIELDS = ("l1", "l2", "lg1", "lg2", "m1", "m2", "Jz1", "Jz2", "J_rotor")


def _plant(slave):
    """The plant presets (plant/presets.py) by name: ``plant_preset_chains`` holds each
    preset's two chains, :data:`PLANT_CHAIN_FIELDS` each."""
    from plant.presets import PRESET_NAMES, get_preset

    presets = [get_preset(name) for name in PRESET_NAMES]
    chains = [[getattr(chain, f) for chain in (p.chain1, p.chain2) for f in PLANT_CHAIN_FIELDS] for p in presets]
    return {}, {"plant_preset_names": list(PRESET_NAMES), "plant_preset_chains": np.array(chains)}


def drive_presets() -> dict:
    """Every motor preset by name (``preset_names``) and its fields in
    :data:`fmus.slave.declarations.MOTOR_PARAMETERS`' order, a row each (``preset_motor``): pcn_drive_setup.h's
    pcn_motor_presets."""
    from fmus.slave.declarations import MOTOR_PARAMETERS
    from motor.presets import MOTOR_PRESETS

    from motor.current_controller import THESIS_POLES

    names = sorted(MOTOR_PRESETS)
    return {"preset_names": names, "preset_motor": np.array([[getattr(MOTOR_PRESETS[n], f) for f, _, _ in
                                                               MOTOR_PARAMETERS] for n in names]),
            "current_poles": np.array(THESIS_POLES, dtype=np.float64)}


def drive_design(slave, suffix: str = "") -> dict:
    """The current controllers (app. C, python-control) a native FMU carries for the slave's
    drive, whatever its mode: first the one designed for the slave's parameters, then those of
    the motor presets at the slave's T (a package's drives of other presets need no FMU of
    their own).  ``design<suffix>_keys``: a row of R, L, kt, ke, b, J_rotor of the design's
    motor and T each; ``design<suffix>_coefficients``: alpha, beta, gamma, delta each (0 if
    the first failed); ``design<suffix>_error``: the first's failure message, or ""."""
    from fmus.slave.declarations import drive_params
    from motor.current_controller import THESIS_POLES
    from motor.drive import _design
    from motor.presets import MOTOR_PRESETS

    params, design = drive_params(slave, suffix)
    keys, coefficients, error = [], [], ""
    for k, p in enumerate([design or params, *(MOTOR_PRESETS[name] for name in sorted(MOTOR_PRESETS))]):
        key = [p.R, p.L, p.kt, p.ke, p.b, p.J_rotor, slave.T]
        if key in keys:
            continue
        try:
            d = _design(p, slave.T, THESIS_POLES)
        except ValueError as exc:
            if k == 0:
                keys.append(key)
                coefficients.append([0.0] * 4)
                error = str(exc)
            continue
        keys.append(key)
        coefficients.append([d.alpha, d.beta, d.gamma, d.delta])
    return {f"design{suffix}_keys": np.array(keys, dtype=np.float64),
            f"design{suffix}_coefficients": np.array(coefficients, dtype=np.float64), f"design{suffix}_error": [error]}


def _drive(slave):
    return {}, {**drive_presets(), **drive_design(slave)}


def _actuated(slave):
    """The plant presets, the motor presets and each drive's current controller (suffix 1, 2)."""
    return {}, {**_plant(slave)[1], **drive_presets(), **drive_design(slave, "1"), **drive_design(slave, "2")}


def _position(slave):
    """The law's set-up data: the strategies' presets (Tables 6-8, seed 001's) per trajectory
    name, each plant preset's geometry and its whole model (``preset_model``: l0, m0 and both
    chains' :data:`PLANT_CHAIN_FIELDS`: the counter-mass check, and the model Ĥ, ĥ the adapter
    makes at set-up with kernels/src/model5r.c), the motor presets' kt
    (so every parameter of the slave stays free in the FMU)."""
    from controller.kinematics import Kinematics
    from controller.position import default_kt
    from controller.strategies import ALL_STRATEGY_NAMES, get_strategy
    from fmus.slaves.parcosim_positioncontroller import MAX_DELAY_STEPS, MAX_TABLE_POINTS
    from plant import fivebar
    from plant.presets import COUNTER_REACH, PRESET_NAMES, get_preset

    trajectories = ("circle", "triangle", "thesis_circle", "hold")
    arrays = {"strategy_names": list(ALL_STRATEGY_NAMES), "trajectory_names": list(trajectories),
              "preset_names": list(PRESET_NAMES)}
    rows = []
    for trajectory in trajectories:
        for name in ALL_STRATEGY_NAMES:
            s = get_strategy(name, trajectory)
            gamma = (0.0, 0.0, 0.0) if s.gamma is None else (1.0, *s.gamma)
            rows.append([{"q": 0.0, "x": 1.0}[s.space], float(s.model_based), s.lam, s.m_star, s.phi, *s.k, *gamma,
                         {"unified": 0.0, "seed001": 1.0}[s.law]])
    arrays["strategies"] = np.array(rows)
    geometry, models = [], []
    for name in PRESET_NAMES:
        preset = get_preset(name)
        kin = Kinematics(preset)
        geometry.append([kin.l0, kin.l11, kin.l12, kin.l21, kin.l22])
        models.append([preset.l0, preset.m0, *(getattr(c, f) for c in (preset.chain1, preset.chain2)
                                               for f in PLANT_CHAIN_FIELDS)])
    arrays["preset_geometry"], arrays["preset_model"] = np.array(geometry), np.array(models)
    kt1, kt2 = default_kt()
    scalars = {"default_kt1": float(kt1), "default_kt2": float(kt2), "band": float(fivebar.NEAR_SINGULAR_MARGIN),
               "max_delay_steps": int(MAX_DELAY_STEPS), "max_table_points": float(MAX_TABLE_POINTS),
               "counter_reach": float(COUNTER_REACH), "strategy_words": len(rows[0])}
    return scalars, arrays


#: Model name -> its native parts; one line a model.
NATIVE = {
    "Derivator": NativeModel("pcn_derivator.c", ("derivator.c",), _derivator, sampled=True),
    "Trajectory": NativeModel("pcn_trajectory.c", ("trajectory.c",), _trajectory),
    "WheeledPendulum": NativeModel("pcn_wheeledpendulum.c", ("wheeled.c",)),
    "BalanceController": NativeModel("pcn_balancecontroller.c", ("balance.c",), _balance, sampled=True),
    "PositionController": NativeModel("pcn_positioncontroller.c",
                                      ("law.c", "kinematics5r.c", "fivebar.c", "model5r.c"), _position, sampled=True),
    "CurrentObserver": NativeModel("pcn_currentobserver.c", ("observer.c", "electrics.c"), _observer, sampled=True),
    "FiveBarPlant": NativeModel("pcn_fivebarplant.c", ("fivebar.c", "kinematics5r.c", "model5r.c"), _plant,
                                parts=("pcn_plant_setup.c", "pcn_plant_setup.h")),
    "DCMotorDrive": NativeModel("pcn_dcmotordrive.c", ("drive.c", "observer.c", "electrics.c", "design.c"), _drive,
                                sampled=True,
                                parts=("pcn_drive_setup.c", "pcn_drive_setup.h")),
    "ActuatedFiveBarPlant": NativeModel(
        "pcn_actuatedfivebarplant.c", ("actuated.c", "fivebar.c", "kinematics5r.c", "model5r.c", "drive.c", "electrics.c", "design.c"),
        _actuated, sampled=True,
        parts=("pcn_plant_setup.c", "pcn_plant_setup.h", "pcn_drive_setup.c", "pcn_drive_setup.h")),
}
