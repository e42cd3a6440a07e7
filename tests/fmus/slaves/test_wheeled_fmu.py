"""The WheeledPendulum and BalanceController FMUs, the balance design and the pendulum scenes."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from controller.balance import BalanceSettings, design_balance
from fmus.slaves.parcosim_wheeledpendulum import OUTPUTS
from plant.wheeled import SEED, WheeledPendulum, upright_linearisation
from scenarios.scenes.pendulum import BALANCED_DEG, PendulumFidelity, pendulum_scene
from scenarios.run.runner import run_scene
from tests.support.fmi_support import FmuInstance

NAMES = [name for name, _ in OUTPUTS]


@pytest.mark.parametrize("model", ["WheeledPendulum", "BalanceController"])
def test_fmpy_validate(built_fmus, model):
    """Catches a WheeledPendulum or BalanceController FMU that fmpy's validation rejects."""
    assert validate_fmu(str(built_fmus[model])) == []


def test_plant_fmu_equals_in_process_to_the_last_bit(built_fmus):
    """Catches a WheeledPendulum FMU that differs from the in-process simulator by a bit."""
    start = {"psi0": 0.1, "dphi0": 1.0, "dtheta0": 2.0}
    fmu = FmuInstance(built_fmus["WheeledPendulum"], start)
    sim = WheeledPendulum(initial={"psi": 0.1, "dphi": 1.0, "dtheta": 2.0})
    for k in range(100):
        tl, tr = 0.05 * math.sin(7e-3 * k), 0.04 * math.cos(5e-3 * k)
        fmu.step(1e-3, tau_l=tl, tau_r=tr)
        sim.step(tl, tr, 1e-3)
        expected = sim.outputs()
        assert [fmu.get(n) for n in NAMES] == [expected[n] for n in NAMES], k
    fmu.close()


def test_fall_is_fmi2discard_naming_psi_and_time(built_fmus):
    """Catches a fall reported as fmi2Error or fmi2Fatal, or without psi and time."""
    fmu = FmuInstance(built_fmus["WheeledPendulum"], {"psi0": 0.3})
    assert not fmu.get("fallen")
    with pytest.raises(FMICallException) as caught:
        for _ in range(3000):
            fmu.step(1e-3)
    assert caught.value.status == 2, "fmi2Discard"
    message = fmu.get("error")
    assert "fell over" in message and "psi = " in message and "t = " in message
    assert fmu.get("fallen") == 1
    assert all(math.isfinite(fmu.get(n)) for n in NAMES) and abs(fmu.get("psi")) < 0.5 * math.pi
    fmu.close()


@pytest.mark.parametrize("parameters, expected", [
    ({"M": -0.6}, "parameter M = -0.6"),
    ({"model": "lagrange"}, "model = 'lagrange'"),
    ({"psi0": 2.0}, "initial psi0 = 2.0 rad is no standing robot (fallen_pitch)"),
    ({"g": float("nan")}, "parameter g = nan"),
])
def test_bad_plant_parameters_refused_by_name(built_fmus, parameters, expected):
    """Catches a WheeledPendulum FMU accepting a bad parameter without naming it."""
    fmu = FmuInstance(built_fmus["WheeledPendulum"], parameters)
    assert expected in fmu.refused_step(1e-3)
    fmu.close()


def test_nan_torque_refused_naming_variable_value_time(built_fmus):
    """Catches a WheeledPendulum FMU accepting NaN torque or naming the wrong input."""
    fmu = FmuInstance(built_fmus["WheeledPendulum"])
    fmu.step(1e-3)
    message = fmu.refused_step(1e-3, tau_r=float("nan"))
    assert "tau_r = nan" in message and "t = 0.001" in message
    fmu.close()


def test_linearisation_matches_finite_differences_of_the_fmu_step():
    """One 1 ms step of the plant slave from perturbed upright states = the ZOH discretisation
    of the analytic linearisation (to the finite difference's own error)."""
    import control

    from fmus.cosim.backends import InProcessInstance

    A, B = upright_linearisation()
    sys_d = control.c2d(control.ss(A, B, np.eye(6), np.zeros((6, 2))), 1e-3)
    names = ["theta", "psi", "phi", "dtheta", "dpsi", "dphi"]
    eps = 1e-6

    def step(start, torques):
        instance = InProcessInstance("WheeledPendulum", "p")
        instance.enter_initialization({f"{n}0": v for n, v in zip(names, start)}, 0.0)
        instance.exit_initialization()
        slave = instance.slave
        slave.tau_l, slave.tau_r = torques
        assert slave.do_step(0.0, 1e-3)
        return np.array([getattr(slave, n) for n in names])

    zero = np.zeros(6)
    Ad = np.column_stack([(step(eps * e, (0, 0)) - step(-eps * e, (0, 0))) / (2 * eps) for e in np.eye(6)])
    Bd = np.column_stack([(step(zero, eps * e) - step(zero, -eps * e)) / (2 * eps) for e in np.eye(2)])
    np.testing.assert_allclose(Ad, sys_d.A, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(Bd, sys_d.B, rtol=1e-6, atol=1e-8)


def test_design_closed_loop_and_observer_poles():
    """Catches a balance design whose closed loop or observer is unstable or not the stated poles."""
    d = design_balance()
    poles = np.linalg.eigvals(d.Ad - d.Bd @ d.K)
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(d.closed_loop_poles), atol=1e-12)
    assert np.max(np.abs(d.closed_loop_poles)) < 1.0 and np.max(np.abs(d.observer_poles)) < 1.0
    assert np.max(np.abs(np.linalg.eigvals(d.Ad))) > 1.0, "the open loop is unstable"
    # the controller needs the observer: psi is not among what it measures
    assert not any(np.array_equal(row, np.eye(6)[1]) for row in d.C)
    locked = design_balance(BalanceSettings(yaw=False))
    assert locked.K.shape == (2, 4) and np.allclose(locked.K[0], locked.K[1])


def test_balance_scene_recovers_from_5_degrees_and_fmus_equal_in_process(built_fmus):
    """Catches a balance loop that does not recover from 5 degrees, or FMUs differing from in process."""
    scene = pendulum_scene("pendulum_balance")
    a = run_scene(scene)
    m = a.metrics
    assert m["completed"] and m["last_second_pitch_deg"] <= BALANCED_DEG
    # released at 5 degrees with psi_hat = 0, it tilts a little further while the observer finds the
    # tilt (5.23 degrees with the Kalman filter gain), and never falls away
    assert 5.0 <= m["peak_pitch_deg"] <= 5.5
    # the observer found the 5 degree tilt it never measured
    t, psi, psi_hat = a.columns["t"], a.columns["psi"], a.columns["psi_hat"]
    late = t > 2.0
    assert np.max(np.abs(psi_hat[late] - psi[late])) < math.radians(0.1)
    short = replace(scene, system=replace(scene.system, stop_time=0.5))
    fmu_dir = next(iter(built_fmus.values())).parent
    b, c = run_scene(short, mode="fmu", fmu_dir=fmu_dir), run_scene(short)
    assert all(np.array_equal(b.columns[k], c.columns[k]) for k in c.columns)


def test_push_and_drive_scenes():
    """Catches push or drive scenes that fall, drift more than 20 mm or miss the 90 degree turn."""
    push = run_scene("pendulum_push").metrics
    assert push["completed"] and 1.0 < push["peak_pitch_deg"] < 15.0 and push["last_second_pitch_deg"] < BALANCED_DEG
    drive = run_scene("pendulum_drive").metrics
    assert drive["completed"] and drive["final_position_error_mm"] < 20.0
    assert drive["final_yaw_deg"] == pytest.approx(90.0, abs=1.0)


def test_falling_run_reports_completed_false():
    """Catches a falling run reported as completed, or without psi in its error."""
    outcome = run_scene(pendulum_scene("pendulum_balance", v_battery=0.3))
    assert outcome.metrics["completed"] is False
    error = outcome.metrics["error"]
    assert "fell over" in error["message"] and "psi = " in error["message"]
    # the fall as data: the plant's kernel refused with the pitch as the variable
    assert (error["kind"], error["instance"], error["variable"], error["unit"]) == ("refused", "plant", "psi", "rad")
    assert abs(error["value"]) >= math.pi / 2 and outcome.metrics["outcome"] == "refused"


@pytest.mark.parametrize("fidelity", [PendulumFidelity(yaw=False), PendulumFidelity(electrics="ideal"),
                                      PendulumFidelity(friction=False), PendulumFidelity(model="seed")])
def test_fidelity_switches_still_balance(fidelity):
    """Catches a pendulum fidelity switch (yaw, friction, model) that breaks balancing."""
    scene = pendulum_scene("pendulum_balance", fidelity)
    outcome = run_scene(scene)
    assert outcome.metrics["completed"] and outcome.metrics["last_second_pitch_deg"] <= BALANCED_DEG
    if not fidelity.yaw:
        assert np.all(outcome.columns["phi"] == 0.0)
    if fidelity.electrics == "ideal":
        assert not any(c.model == "DCMotorDrive" for c in scene.system.components)


def test_sample_time_quick_checks():
    """The sweep's ends (docs/pendulum.md): balanced at 2 ms, fallen at 10 ms."""
    from scenarios.studies.pendulum_trade import sample_time_rows

    slow, fast = sample_time_rows((10e-3, 2e-3))
    assert not slow["completed"] and "fell over" in slow["error"]
    assert fast["balanced"]


def test_generic_commands_on_a_pendulum_scene(tmp_path, capsys):
    """Catches a 5R-only command option accepted on a pendulum scene instead of refused in one line."""
    from parcosim.cli import main

    assert main(["export-ssp", "pendulum_balance", str(tmp_path / "p.ssp")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--per-component" in err[0]
    assert main(["run", "pendulum_balance", "--drives-in-plant", "4", "--out", str(tmp_path / "d")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert main(["trade", "pendulum_push", "--quick", "--out", str(tmp_path / "t")]) == 0
    text = (tmp_path / "t" / "trade.md").read_text()
    assert "| defaults |" in text and "| ideal electrics |" in text


@pytest.mark.parametrize("T", [0.5e-5, 1.5, float("nan")])
def test_balance_sample_time_out_of_range_is_refused(T):
    """The balance controller's T must lie in [MIN_SAMPLE_TIME, 1] s, both ends."""
    from controller.balance import MIN_SAMPLE_TIME, BalanceSettings

    assert MIN_SAMPLE_TIME == 1e-5
    with pytest.raises(ValueError, match=r"parameter T = .* s must be in \[1e-05, 1\] s"):
        BalanceSettings(T=T).validate()
    BalanceSettings(T=MIN_SAMPLE_TIME).validate()


def test_balance_controller_commands_nothing_before_its_first_sample(built_fmus):
    """A Jacobi master (Ecos, libcosim, fmpy's SSP runner) feeds the drives the controller's
    outputs as they are after initialisation, before the controller has sampled anything: at
    rest those must be no voltage and no torque, else the first step kicks the pendulum."""
    fmu = FmuInstance(built_fmus["BalanceController"], {})
    assert [fmu.get(n) for n in ("v_l", "v_r", "tau_l", "tau_r")] == [0.0, 0.0, 0.0, 0.0]
    fmu.close()


def test_ideal_torques_are_the_stalled_motors_torques_per_wheel():
    """Each wheel's ideal torque is what its motor gives at stall for its own voltage: with
    L = 0 and ω = 0, (4.162) leaves i = v / R and τ = kt i (seed 000's quasi-static drive).
    Asymmetric encoders make the two voltages differ, so swapped or lost outputs show."""
    from controller.balance import BalanceController
    from motor import get_motor_preset

    design = design_balance(BalanceSettings())
    motor = get_motor_preset(design.settings.motor_preset)
    controller = BalanceController(design)
    for t, (enc_l, enc_r, gyro) in enumerate([(0.01, -0.02, 0.1), (0.02, -0.03, -0.05), (0.0, 0.04, 0.2)]):
        v_l, v_r = controller.sample(1e-3 * t, enc_l, enc_r, gyro)
        assert abs(v_l - v_r) > 1e-3
        for v, tau in zip((v_l, v_r), controller.ideal_torques()):
            assert tau == pytest.approx(motor.kt * (v / motor.R), rel=1e-15, abs=0.0)
