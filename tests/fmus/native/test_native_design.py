"""Native FMUs whose designs are made in C at their set-up (kernels/src/design.c) against their
pythonfmu twins, which design with python-control at initialisation (issue 28).

The drives' current controller for motor values outside the designs a native FMU carries (its
build's, the motor presets' at its T): python-control's coefficients are themselves off the
exact design by up to 5e-11 relative (its 4x4 solve is near singular,
tests/kernels/test_kernels_design.py), design.c's within 1e-15; the slow mode K(z) cancels
(delta near 1) carries that difference into the outputs some ten times amplified (7 to 14
measured).  So the drive's outputs are compared within 30 times python-control's own error (measured here against the
design in 50 digits) plus 1e-12 of each output's peak: a wrong design (a pole, the zero, a motor
value misread) moves them by far more.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from motor.presets import MOTOR_PRESETS
from tests.fmus.native.test_native_equality import SCENARIOS, compare
from tests.kernels.test_kernels_design import exact_design, python_control_design
from tests.support.fmu_calls import Driver

pytestmark = [pytest.mark.fmu]

#: Motor parameters of no preset (DCMotorDrive's variables), the design's motor they give, T.
DRIVE_DESIGNS = [
    ({"R_design": 2.0}, replace(MOTOR_PRESETS["motor1"], R=2.0), 1e-3),
    ({"preset": "motor2", "kt": 0.05}, replace(MOTOR_PRESETS["motor2"], kt=0.05), 1e-3),
    ({"L": 1e-3}, replace(MOTOR_PRESETS["motor1"], L=1e-3), 1e-3),
    ({"J_design": 2e-4}, replace(MOTOR_PRESETS["motor1"], J_rotor=2e-4), 1e-3),
    ({"b": 0.0, "b_design": 1e-4}, replace(MOTOR_PRESETS["motor1"], b=1e-4), 1e-3),
    ({"preset": "motor2", "T": 2e-3}, MOTOR_PRESETS["motor2"], 2e-3),
    ({"R": 0.6, "L": 3e-4, "ke": 0.03, "kt": 0.031, "J_design": 5e-5, "b": 3e-5},
     replace(MOTOR_PRESETS["motor1"], R=0.6, L=3e-4, ke=0.03, kt=0.031, J_rotor=5e-5, b=3e-5), 1e-3),
]


def python_control_error(motor, T) -> float:
    """python-control's design off the exact one, relative to its largest coefficient."""
    _, reference = python_control_design(motor, T)
    exact = exact_design(motor, T)
    return float(np.abs(reference - exact).max() / np.abs(exact).max())


@pytest.mark.parametrize("parameters, motor, T", DRIVE_DESIGNS)
def test_drive_designs_in_c_for_motor_values_it_carries_no_design_of(parameters, motor, T, native_fmus, twin_fmus):
    """The native DCMotorDrive accepts motor values away from every carried design (it refused
    them by name until design.c) and runs the equality script (steps, FMU state, refusals) as
    its twin: same statuses and messages, outputs within the twin's own design error.  Catches
    a C design of other poles or another plant (differences of 1e-3 and more), a design value
    taken from the preset in place of the override, a carried design used for other values."""
    base = SCENARIOS["DCMotorDrive"]
    scenario = base if T == 1e-3 else replace(base, h=T)
    tolerance = 30.0 * python_control_error(motor, T) + 1e-12
    compare(twin_fmus["DCMotorDrive"], native_fmus["DCMotorDrive"], scenario, parameters, tolerance=tolerance)
    assert tolerance < 2e-9


@pytest.mark.parametrize("parameters, motors", [
    ({"R_design1": 2.0, "L2": 1e-3}, (replace(MOTOR_PRESETS["motor1"], R=2.0), replace(MOTOR_PRESETS["motor2"],
                                                                                       L=1e-3))),
    ({"preset2": "motor2", "kt2": 0.05, "J_design1": 2e-4},
     (replace(MOTOR_PRESETS["motor1"], J_rotor=2e-4), replace(MOTOR_PRESETS["motor2"], kt=0.05))),
])
def test_actuated_plant_designs_each_drive_in_c(parameters, motors, native_fmus, twin_fmus):
    """The drives inside the plant: each drive's off-preset design made in C, the script run as
    the twin's within 100 times the twin's own design error (the mechanism, driven by the
    currents, carries a torque difference on into its rates: 30 to 40 times measured).  Catches
    the suffixes' parameters read for the wrong drive."""
    tolerance = 100.0 * max(python_control_error(m, 1e-3) for m in motors) + 1e-12
    compare(twin_fmus["ActuatedFiveBarPlant"], native_fmus["ActuatedFiveBarPlant"], SCENARIOS["ActuatedFiveBarPlant"],
            parameters, tolerance=tolerance)


#: The controller's plant and grid parameters away from the build's (the native FMU refused them
#: by name for a model-based strategy until model5r.c): the exact and tabulated models.
CONTROLLER_MODELS = [
    {"strategy": "TCMDx", "gravity_y": -9.81, "counter_mass1": 0.4, "counter_mass2": 0.25, "model_error": 0.1},
    {"strategy": "TCx", "model": "exact", "gravity_x": 1.0, "gravity_y": -9.81, "counter_mass2": 0.3,
     "model_error": -0.2},
    {"strategy": "SMCx", "grid_step": 0.008, "x_min": -0.15, "x_max": 0.1, "y_min": 0.05, "y_max": 0.3},
    {"strategy": "TCMDq", "grid_step": 0.004, "x_min": -0.1, "x_max": 0.125, "y_min": 0.08, "y_max": 0.2,
     "model_error": 0.05, "counter_mass1": 0.2, "gravity_y": -9.81},
    {"strategy": "SMCq", "model_error": 0.3, "grid_step": 0.006, "counter_mass2": 0.1},
]


@pytest.mark.parametrize("parameters", CONTROLLER_MODELS)
def test_controller_makes_its_model_in_c_for_any_plant_and_grid(parameters, native_fmus, twin_fmus):
    """The native PositionController makes its model (the exact model's parameters, the table)
    at set-up from the presets it carries and runs the equality script as the twin, which makes
    it in Python at initialisation (cache off), within 1e-12 of each output's peak (bit for bit
    measured), the table's fallbacks counted alike.  Catches a model of the unperturbed or
    counter-mass-free plant, a gravity not given to the model, a grid of the build's step or
    bounds (the pose leaving a narrower table refuses or falls back at other samples)."""
    trace = compare(twin_fmus["PositionController"], native_fmus["PositionController"],
                    SCENARIOS["PositionController"], {**parameters, "cache": False})
    assert [s.status for s in trace if s.call[0] == "step"].count(0) > 250   # the model is used


def test_controller_state_restored_into_an_instance_never_set_up_makes_its_model(native_fmus):
    """The model lives in scratch (configuration of the parameters): an instance given the same
    parameters but never initialised takes a serialised state of a running one and steps on as
    it does, bit for bit, the table and the perturbed model made at its first sample.  Catches
    a model read from scratch that was never filled (a zero table: every pose a hole) or made
    for the build's parameters."""
    parameters = {**CONTROLLER_MODELS[3], "cache": False}
    inputs = SCENARIOS["PositionController"].inputs
    h, outs = 1e-3, ["tau1", "tau2", "i_ref1", "i_ref2", "e1", "e2", "model_fallbacks", "error"]
    running = Driver(native_fmus["PositionController"], "a")
    script = [("set", parameters), ("setup", 0.0), ("enter",), ("exit",)]
    script += [c for k in range(30) for c in (("set", inputs(k, k * h)), ("step", k * h, h))]
    assert all(s.status == 0 for s in running.run(script + [("getstate", "s"), ("serialize", "s")]))
    fresh = Driver(native_fmus["PositionController"], "b")
    assert all(s.status == 0 for s in fresh.run([("set", parameters), ("bytes", "s", running.states["s"]),
                                                 ("deserialize", "s"), ("setstate", "s")]))
    reads = []
    for driver in (running, fresh):
        steps = [c for k in range(30, 140) for c in (("set", inputs(k, k * h)), ("step", k * h, h), ("get", outs))]
        trace = driver.run(steps)
        assert [s.status for s in trace].count(0) == len(trace)
        reads.append([s.result for s in trace if s.call[0] == "get"])
    assert reads[0] == reads[1] and max(r[6] for r in reads[0]) > 0   # the table's fallback reached too
