"""The monolithic reference's discrete parts on short runs (scenarios/reference.py), each
recorded sample against its definition computed here from the recorded inputs it was taken
from, for both drives (the long runs are of the slow kind, tests/scenarios/run/
test_reference_monolithic.py; issue 31: results against an independent formulation, every
instance of a repeated part)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from motor import CurrentController, design_current_controller, get_motor_preset, shaft_torque
from scenarios.reference import reference_run
from scenarios.scenes.catalogue import get_scene

STOP = 0.05


def _run(name: str):
    system = replace(get_scene(name).system, stop_time=STOP)
    return system, reference_run(system)


def _source(system, target: str) -> str:
    """The output wired to the input ``target``."""
    return next(c.source for c in system.connections if c.target == target)


def _drives(system) -> list:
    return [c for c in system.components if c.model == "DCMotorDrive"]


@pytest.fixture(scope="module")
def bench():
    return _run("bench_circle_TCMDx")


def test_each_drive_samples_its_controller_on_its_own_current_reference_and_estimate(bench):
    """Row k + 1 holds what was sampled at t_k (Gauss-Seidel order): each drive's voltage is
    its current controller K(z) on the i_ref and the i_hat wired to it, of that same row, run
    from rest.  Catches the drive's sample given its inputs in another order (the voltage
    reference for the estimate), a drive given the other's inputs, or a sample out of its row."""
    system, ref = bench
    assert ref.completed and len(ref.time) == round(STOP / system.step) + 1
    for drive in _drives(system):
        p = get_motor_preset(drive.parameters["preset"])
        controller = CurrentController(design_current_controller(p), p.v_max)
        i_ref = ref[_source(system, f"{drive.name}.i_ref")]
        i_hat = ref[_source(system, f"{drive.name}.i_hat")]
        expected = [controller.update(a, b) for a, b in zip(i_ref[1:], i_hat[1:])]
        v = ref[f"{drive.name}.v"]
        assert np.allclose(v[1:], expected, rtol=0, atol=1e-12), drive.name
        assert np.abs(v).max() > 1.0, drive.name     # the loop drove the motor


def test_each_observer_and_torque_are_their_formulas_of_the_wired_signals(bench):
    """Each observer's estimate at row k + 1 is (v_k - ke omega_{k+1}) / R of the voltage of the
    interval before and the derivator's speed wired to it; each drive's shaft torque is B.2 of
    its current and the plant's speed wired to it.  Catches a drive's or an observer's signals
    taken from the other joint, or the torque of another speed."""
    system, ref = bench
    for drive in _drives(system):
        p = get_motor_preset(drive.parameters["preset"])
        observer = _source(system, f"{drive.name}.i_hat").split(".")[0]
        i_hat, speed = ref[f"{observer}.i_hat"], ref[_source(system, f"{observer}.omega")]
        v = ref[_source(system, f"{observer}.v")]
        assert np.allclose(i_hat[1:], (v[:-1] - p.ke * speed[1:]) / p.R, rtol=0, atol=1e-12), observer
        omega = ref[_source(system, f"{drive.name}.omega")]
        torque = [shaft_torque(i, w, p) for i, w in zip(ref[f"{drive.name}.i"], omega)]
        assert np.allclose(ref[f"{drive.name}.tau"], torque, rtol=0, atol=1e-15), drive.name
        assert np.abs(ref[f"{drive.name}.tau"]).max() > 1e-3, drive.name


def test_the_twins_drives_sample_their_own_pwm_voltage_from_their_own_inputs():
    """The bench twin's drives (PWM of 960 counts, current noise and offset, LuGre): each
    voltage is a multiple of its quantum v_max / pwm_counts, and moves with the drive's
    i_ref.  Catches a sample taken without the drive's own quantisation (the controller's raw
    output), or from inputs in another order."""
    system, ref = _run("bench_real_circle_TCMDq")
    assert ref.completed
    for drive in _drives(system):
        quantum = get_motor_preset(drive.parameters["preset"]).v_max / drive.parameters["pwm_counts"]
        v = ref[f"{drive.name}.v"]
        steps = v / quantum
        assert np.max(np.abs(steps - np.round(steps))) < 1e-9, drive.name
        assert np.abs(steps).max() > 10, drive.name
        i_ref = ref[_source(system, f"{drive.name}.i_ref")]
        assert np.corrcoef(v[1:], i_ref[1:])[0, 1] > 0.5, drive.name
