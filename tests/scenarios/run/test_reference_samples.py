"""The monolithic reference's discrete parts on short runs (scenarios/reference.py), each
recorded sample against its definition computed here from the recorded inputs it was taken
from, for both drives (the long runs are of the slow kind, tests/scenarios/run/
test_reference_monolithic.py), and the model pieces it adds (moved here from there: they
are quick; issue 31: results against an independent formulation, every
instance of a repeated part)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from fmus.cosim.system import Component, System
from motor import (CurrentController, advance_current, armature_current_rate, design_current_controller,
                   electrical_step_coefficients, get_motor_preset, shaft_torque)
from scenarios.reference import ReferenceError, _mean_torque, reference_run
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


# --- the model pieces the reference adds ----------------------------------------------------

@pytest.mark.parametrize("preset", ["motor1", "motor2"])
def test_current_rate_integrates_to_the_drives_exact_step(preset):
    """L di/dt = v - R i - ke w, integrated with v, w held, is the drive's own exact step.
    Catches the reference's current rate with a term of another sign or another motor's
    constant."""
    p = get_motor_preset(preset)
    h, i0, v, w = 1e-3, 0.7, 9.0, -12.0
    sol = solve_ivp(lambda t, i: [armature_current_rate(i[0], v, w, p)], (0.0, h), [i0], method="DOP853",
                    rtol=1e-13, atol=1e-15)
    exact = advance_current(i0, v, w, p.ke, electrical_step_coefficients(p.R, p.L, h, "exact"))
    assert sol.y[0, -1] == pytest.approx(exact, abs=1e-11)


@pytest.mark.parametrize("preset", ["motor1", "motor2"])
def test_mean_torque_is_the_step_average(preset):
    """Catches a reference's mean drive torque that is not the step average of the drive's torque."""
    class _Slave:  # what _mean_torque reads of a drive slave
        class drive:
            params = get_motor_preset(preset)

    p = _Slave.drive.params
    h, i0, v, w = 1e-3, -2.0, 15.0, 3.0

    def current(s):
        return advance_current(i0, v, w, p.ke, electrical_step_coefficients(p.R, p.L, s, "exact")) if s > 0 else i0

    mean = quad(lambda s: shaft_torque(current(s), w, p), 0.0, h, epsabs=1e-15)[0] / h
    assert _mean_torque(_Slave, i0, v, w, h) == pytest.approx(mean, abs=1e-12)


def test_refuses_what_it_cannot_integrate():
    """Catches a reference run on a system without exactly one plant, or with another coupling."""
    system = System((Component("traj", "Trajectory", {}),), (), ("traj.x_d",), stop_time=0.01)
    with pytest.raises(ReferenceError, match="exactly one FiveBarPlant"):
        reference_run(system)
    with pytest.raises(ValueError, match="coupling"):
        reference_run("bench_circle_TCMDx", stop_time=0.01, coupling="jacobi")


@pytest.mark.parametrize("name", ["bench_circle_TCMDx", "bench_real_circle_TCMDq"])
def test_the_mean_torque_what_if_is_the_cosim_coupling_when_each_drive_outputs_its_mean(name):
    """With ``torque_output = "mean"`` a drive already hands the plant its torque averaged over
    the step, so the ``"mean"`` what-if (the plant held at the mean torque: B.2 of the exact
    current's mean for the ideal drives, the drive's own mean for LuGre ones) gives the rows of
    the co-simulation's coupling, every signal to 1e-12, while the monolithic reference differs
    by the coupling error (> 1e-7 m).  Catches the mean torque of another current, speed or
    step, the plant given the torque at the sample instead, a LuGre drive's mean not its own."""
    system = replace(get_scene(name).system, stop_time=STOP)
    assert all(c.parameters["torque_output"] == "mean" for c in _drives(system))
    mean = reference_run(system, coupling="mean")
    cosim = reference_run(system, coupling="cosim")
    assert mean.completed and cosim.completed and mean.signals.keys() == cosim.signals.keys()
    assert max(np.max(np.abs(mean[s] - cosim[s])) for s in mean.signals) < 1e-12
    monolithic = reference_run(system)
    assert np.max(np.hypot(monolithic["plant.x"] - cosim["plant.x"], monolithic["plant.y"] - cosim["plant.y"])) > 1e-7


def test_the_mean_what_if_of_a_lugre_drive_with_the_torque_at_the_end_stops_naming_it():
    """A LuGre drive whose torque output is the step's end: the what-if cannot take its mean, the
    run stops at its first step with the drive's refusal, the initial row kept.  Catches the
    what-if run with the end torque as if it were the mean."""
    from scenarios.reference import with_parameters

    system = with_parameters(replace(get_scene("bench_real_circle_TCMDq").system, stop_time=STOP), "drive1",
                             torque_output="end")
    run = reference_run(system, coupling="mean")
    assert not run.completed and len(run.time) == 1
    assert run.error == ("drive1 refused the step from t = 0 s: drive drive1: the 'mean' what-if of a LuGre drive "
                         "needs torque_output = 'mean' (its own mean torque)")
