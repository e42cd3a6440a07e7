"""The drive's bench-twin options: LuGre friction, PWM resolution, current-loop offset and noise.

In the Python drive, the DCMotorDrive FMU, the compiled loop and the scenes' Fidelity; the
LuGre model itself is tested against the paper in tests/motor/test_friction.py.
"""
from __future__ import annotations

import copy
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

# The compiled loop hashes its kernels' source: import them from the worktree before an FMU
# loaded in this process imports its own bundled (temporary) copies under the same names.
import controller.fastderivator  # noqa: F401
import controller.fasttrajectory  # noqa: F401
import plant.fast5r  # noqa: F401
from motor import Drive, friction as fr, kernel, motor1
from motor.drive import gaussian
from tests.support.fmi_support import FmuInstance

H = 1e-3


def _speeds(n=400, seed=3):
    """A speed history through rest, reversals and sliding [rad/s]."""
    t = np.arange(n) * H
    return 3.0 * np.sin(2 * np.pi * 2.0 * t) * np.exp(-3.0 * t) + 0.02 * np.random.default_rng(seed).standard_normal(n)


@pytest.mark.parametrize("torque_output", ["mean", "end"])
def test_lugre_drive_is_kt_i_minus_the_pure_models_friction(torque_output):
    """Drive(friction='lugre'): tau = kt i - F, F the LuGre step of motor/friction.py over the
    same speeds (mean or end of the step), the currents those of a frictionless drive."""
    lugre = Drive(motor1, friction="lugre", torque_output=torque_output)
    plain = Drive(motor1.with_(mu=0.0, b=0.0), torque_output=torque_output, design_params=motor1)
    f = fr.new_lugre(fr.LuGre.of_motor(motor1))
    z = 0.0
    for k, omega in enumerate(_speeds()):
        i_ref = 0.5 * math.sin(7.0 * k * H)
        tau, v, i = lugre.step(i_ref, 0.0, omega, lugre.i, H)
        tau0, v0, i0 = plain.step(i_ref, 0.0, omega, plain.i, H)
        z, f_end, f_mean = fr.advance(f, z, omega, H)
        assert (v, i) == (v0, i0)
        assert tau == pytest.approx(tau0 - (f_mean if torque_output == "mean" else f_end), rel=1e-12, abs=1e-15)
        assert lugre.z == z


def test_refused_step_leaves_the_bristles():
    """Catches a LuGre drive whose bristle state z changes on a refused step."""
    drive = Drive(motor1, friction="lugre")
    drive.step(0.3, 0.0, 0.5, 0.0, H)
    z = drive.z
    with pytest.raises(ValueError, match="omega"):
        drive.step(0.3, 0.0, math.nan, 0.0, H)
    with pytest.raises(ValueError, match="h must divide"):
        drive.step(0.3, 0.0, 0.5, 0.0, 0.7e-3)
    assert drive.z == z


def test_lugre_drive_holds_a_torque_below_break_away_and_slips_above():
    """The free rotor against its drive's friction, the motor torque ramped up over 0.3 s:
    below mu (0.85 mu) the rotor only deflects the bristles (presliding, ~ torque / sigma0),
    above mu_s (1.2 mu_s) it turns."""
    for torque, moves in ((0.85 * motor1.mu, False), (1.2 * motor1.mu_s, True)):
        drive = Drive(motor1, friction="lugre", torque_output="mean")
        omega, angle = 0.0, 0.0
        for k in range(1000):
            i_ref = min(1.0, k / 300) * torque / motor1.kt
            tau, _, _ = drive.step(i_ref, 0.0, omega, drive.i, H)
            omega += H * tau / motor1.J_rotor
            angle += H * omega
        if moves:
            assert angle > 0.1
        else:
            assert torque / motor1.sigma0 < angle < 2.0 * torque / motor1.sigma0


def test_pwm_applies_multiples_of_the_quantum_the_controller_keeps_its_own_output():
    """Catches PWM that applies an unquantised voltage or feeds the quantised one back to the controller."""
    counts = 255
    q = motor1.v_max / counts
    pwm = Drive(motor1, pwm_counts=counts)
    ideal = Drive(motor1)
    for k, omega in enumerate(_speeds(200)):
        ideal.buf[:] = pwm.buf
        ideal.buf[kernel.DRIVE["pwm_quantum"]] = 0.0
        ideal._controller_buf[:] = pwm._controller_buf
        i_ref, i_hat = 2.0 * math.sin(9.0 * k * H), pwm.i
        _, v, _ = pwm.step(i_ref, 0.0, omega, i_hat, H)
        _, v_ideal, _ = ideal.step(i_ref, 0.0, omega, i_hat, H)
        assert abs(v / q - round(v / q)) < 1e-9
        assert abs(v - v_ideal) <= 0.5 * q + 1e-12
        assert pwm._controller_buf[kernel.CONTROLLER["u1"]] == v_ideal      # unquantised memory


def test_noise_is_a_stateless_standard_normal():
    """Catches current noise that is not N(0, 1), depends on call order, or correlates across streams."""
    g = np.array([gaussian(11, 1, k) for k in range(20000)])
    assert g[17] == gaussian(11, 1, 17)
    assert stats.kstest(g, "norm").pvalue > 1e-3
    other = np.array([gaussian(11, 2, k) for k in range(20000)])
    assert abs(np.corrcoef(g, other)[0, 1]) < 0.03
    assert abs(np.corrcoef(g[:-1], g[1:])[0, 1]) < 0.03
    assert gaussian(12, 1, 17) != g[17]


def test_offset_and_noise_enter_the_loops_sample():
    """First sample at rest with i_ref = i_hat = 0: v = alpha (0 - offset - sigma n(seed, instance, 0))."""
    offset, sigma, seed, instance = 0.05, 0.1, 7, 2
    drive = Drive(motor1, current_offset=offset, current_noise=sigma, noise_seed=seed, noise_instance=instance)
    alpha = drive.controller.design.alpha
    _, v, _ = drive.step(0.0, 0.0, 0.0, 0.0, H)
    assert v == pytest.approx(-alpha * (offset + sigma * gaussian(seed, instance, 0)), rel=1e-12)
    again = copy.deepcopy(drive)
    assert [drive.step(0.1, 0.0, 0.0, 0.0, H)[1] for _ in range(5)] == \
           [again.step(0.1, 0.0, 0.0, 0.0, H)[1] for _ in range(5)]


@pytest.mark.parametrize("kwargs, words", [
    ({"friction": "coulomb"}, "friction must be one of 'tanh', 'lugre'; got 'coulomb'"),
    ({"pwm_counts": -1}, "pwm_counts must be a whole number in"),
    ({"pwm_counts": 2.5}, "pwm_counts must be a whole number in"),
    ({"current_noise": -0.1}, "current_noise must be >= 0, got -0.1"),
    ({"current_offset": math.inf}, "current_offset must be a finite number, got inf"),
    ({"noise_seed": -3}, "noise_seed must be a whole number in"),
    ({"friction": "lugre", "params": motor1.with_(mu_s=0.01)}, r"mu_s\) = 0.01 must be >= the Coulomb torque"),
    ({"friction": "lugre", "params": motor1.with_(mu=0.0)}, r"Fc \(mu\) = 0.0 must be > 0"),
])
def test_bad_options_are_named(kwargs, words):
    """Catches a drive accepting a bad twin option (friction, PWM, offset, noise) without naming it."""
    params = kwargs.pop("params", motor1)
    with pytest.raises(ValueError, match=words):
        Drive(params, **kwargs)


@pytest.mark.parametrize("field, value", [("sigma0", -5.0), ("sigma1", -0.1), ("omega_s", 0.0), ("mu_s", -0.2)])
def test_motor_params_refuse_bad_lugre_values(field, value):
    """Catches motor parameters accepting a negative or zero LuGre coefficient."""
    with pytest.raises(ValueError, match=f"{field} must be"):
        motor1.with_(**{field: value})


# --- the FMU -----------------------------------------------------------------------------------

TWIN = {"friction": "lugre", "pwm_counts": 1000, "current_offset": 0.02, "current_noise": 0.05,
        "noise_seed": 5, "noise_instance": 1, "torque_output": "mean"}


def test_fmu_matches_the_python_drive_and_restores_its_noise(built_fmus):
    """Catches a twin drive FMU that differs from the Python drive or replays other noise after a state restore."""
    fmu = FmuInstance(built_fmus["DCMotorDrive"], {**TWIN, "sigma0": 80.0})
    drive = Drive(motor1.with_(sigma0=80.0), **TWIN)
    try:
        speeds = _speeds(60)
        for k, omega in enumerate(speeds[:30]):
            fmu.step(H, i_ref=0.4, omega=omega, i_hat=drive.i)
            expected = drive.step(0.4, 0.0, omega, drive.i, H)
            assert (fmu.get("tau"), fmu.get("v"), fmu.get("i")) == expected
        state = fmu.fmu.getFMUstate()
        t = fmu.time
        first = []
        for omega in speeds[30:]:
            fmu.step(H, i_ref=0.4, omega=omega, i_hat=0.1)
            first.append((fmu.get("tau"), fmu.get("v")))
        fmu.fmu.setFMUstate(state)
        fmu.time = t
        for omega, row in zip(speeds[30:], first):
            fmu.step(H, i_ref=0.4, omega=omega, i_hat=0.1)
            assert (fmu.get("tau"), fmu.get("v")) == row
    finally:
        fmu.close()


@pytest.mark.parametrize("name, value, words", [
    ("sigma0", -5.0, "parameter sigma0 = -5.0 is negative"),
    ("mu_s", 0.01, "mu_s) = 0.01 must be >= the Coulomb torque"),
    ("pwm_counts", -2, "pwm_counts must be a whole number"),
])
def test_fmu_refuses_bad_values_naming_them(built_fmus, name, value, words):
    """Catches a drive FMU accepting a bad twin parameter without naming it."""
    fmu = FmuInstance(built_fmus["DCMotorDrive"], {"friction": "lugre", name: value})
    try:
        assert words in fmu.refused_step(H)
    finally:
        fmu.close()


# --- scenes: Fidelity, in process vs compiled ---------------------------------------------------

def _short(scene, stop=0.6):
    return replace(scene, system=replace(scene.system, stop_time=stop))


def test_fidelity_twin_runs_compiled_as_in_process_and_numbers_do_not_change_the_loop():
    """Catches twin options that the compiled loop applies differently from in process."""
    from fmus.cosim.master import simulate
    from scenarios.scenes.thesis import Fidelity, bench

    twin = Fidelity(friction="lugre", pwm_counts=500, current_offset=0.01, current_noise=0.03, noise_seed=4)
    scene = _short(bench("TCMDq", "circle", fidelity=twin))
    a = simulate(scene.system, mode="inprocess")
    b = simulate(scene.system, mode="compiled")
    assert "fallback" not in b.extra and b.extra["python_steps"] == 0
    rows = lambda r: np.column_stack([r.signals[k] for k in scene.system.record])   # noqa: E731
    assert a.completed and np.array_equal(rows(a), rows(b))
    other = replace(twin, noise_seed=9, current_noise=0.05, drive_parameters=(("sigma0", 60.0),))
    c = simulate(_short(bench("TCMDq", "circle", fidelity=other)).system, mode="compiled")
    assert c.extra["plan"] == b.extra["plan"]
    assert c.completed and not np.array_equal(rows(c), rows(b))
    drives = [comp for comp in scene.system.components if comp.model == "DCMotorDrive"]
    assert [d.parameters["noise_instance"] for d in drives] == [1, 2]


def test_fidelity_refuses_what_it_cannot_model():
    """Catches a Fidelity combining LuGre without Coulomb, or twin effects on a scene without drives."""
    from scenarios.scenes.thesis import Fidelity

    with pytest.raises(ValueError, match="friction = 'lugre' models the dry friction that coulomb = False"):
        Fidelity(friction="lugre", coulomb=False)
    for effect in ({"current_noise": 0.1}, {"current_offset": -0.05}, {"pwm_counts": 960}, {"noise_seed": 4},
                   {"friction": "lugre"}, {"drive_parameters": (("mu_s", 0.06),)}):
        with pytest.raises(ValueError, match="electrics = 'ideal' has no drives"):
            Fidelity(electrics="ideal", **effect)
    assert Fidelity(electrics="ideal", current_noise=0.0, noise_seed=0).drive_options() == {}
    with pytest.raises(ValueError, match="friction = 'stribeck'"):
        Fidelity(friction="stribeck")
    assert Fidelity().drive_options() == {}


def test_lugre_inside_the_actuated_plant_runs_compiled_as_in_process_and_near_the_separate_drives():
    """drives_in_plant: the bristles advance per step with the speed held inside the plant, as
    in the separate drive; the rest (currents, mechanism, sigma2 = b) is integrated together."""
    from fmus.cosim.master import simulate
    from scenarios.run.metrics import rms_norm
    from scenarios.scenes.thesis import Fidelity, bench
    from scenarios.scenes.transforms import drives_in_plant

    twin = Fidelity(friction="lugre", pwm_counts=1000, current_noise=0.02, noise_seed=3)
    separate = _short(bench("PDq", "circle", fidelity=twin), 1.0)
    inside = drives_in_plant(separate)
    params = inside.system.component("plant").parameters
    assert (params["friction1"], params["noise_instance2"]) == ("lugre", 2)
    a = simulate(inside.system, mode="inprocess")
    b = simulate(inside.system, mode="compiled")
    rows = lambda r: np.column_stack([r.signals[k] for k in inside.system.record])   # noqa: E731
    assert a.completed and b.extra["python_steps"] == 0 and np.array_equal(rows(a), rows(b))
    c = simulate(separate.system, mode="compiled")
    gap = rms_norm(a["plant.x"] - c["plant.x"], a["plant.y"] - c["plant.y"])
    error = rms_norm(c["plant.x"] - c["traj.x_d"], c["plant.y"] - c["traj.y_d"])
    assert gap < 0.01 * error     # measured 0.2 %; LuGre vs tanh friction moves the path by 8 %
