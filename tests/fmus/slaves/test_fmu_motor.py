"""The DCMotorDrive and CurrentObserver FMUs through fmpy: validation, exactness,
bit-identity with the in-process motor models, the observer in the loop, and
clean refusals of bad input."""
import math
import subprocess
import sys

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from fmus.slaves.parcosim_dcmotordrive import OUTPUTS as DRIVE_OUTPUTS
from motor import CurrentObserver, Drive, get_motor_preset, motor1
from tests.support.fmi_support import FmuInstance
from tests.support.motor_loops import current_step
from tests.support.paths import ROOT

T = 1e-3


@pytest.fixture(scope="module")
def drive_fmu(built_fmus):
    return built_fmus["DCMotorDrive"]


@pytest.fixture(scope="module")
def observer_fmu(built_fmus):
    return built_fmus["CurrentObserver"]


@pytest.mark.parametrize("model", ["DCMotorDrive", "CurrentObserver"])
def test_fmpy_validate_finds_no_problem(built_fmus, model):
    """Catches a DCMotorDrive or CurrentObserver FMU that fmpy's validation rejects."""
    assert validate_fmu(str(built_fmus[model])) == []


@pytest.mark.parametrize("model, outputs, sentinels", [
    ("DCMotorDrive", {"tau", "v", "i"}, {"R", "L", "kt", "ke", "b", "mu", "v_max", "omega_eps", "J_design"}),
    ("CurrentObserver", {"i_hat"}, {"R", "ke", "L"}),
])
def test_variables_structure_and_sentinel_defaults(built_fmus, model, outputs, sentinels):
    """Catches a drive or observer FMU declaring feedthrough, missing an output, or losing a sentinel default."""
    md = read_model_description(str(built_fmus[model]))
    assert {o.variable.name for o in md.outputs} == outputs | {"error", "refusal"}
    assert all(o.dependencies == [] for o in md.outputs)       # outputs change only in doStep
    variables = {v.name: v for v in md.modelVariables}
    for name in sentinels:
        assert variables[name].causality == "parameter"
        assert float(variables[name].start) == -1.0 and "-1: the preset's value" in variables[name].description


# --- voltage mode: exact for a held voltage ----------------------------------------------------------

def analytic_locked_current(t, switch_times, voltages, R, L):
    """i(t) of L di/dt + R i = v(t), i(0) = 0, v piecewise constant: superposed step responses."""
    i, previous = 0.0, 0.0
    for s, v in zip(switch_times, voltages):
        if s <= t:
            i += (v - previous) / R * -math.expm1(-R * (t - s) / L)
            previous = v
    return i


@pytest.mark.parametrize("L_over_R_per_step", [None, 0.01])      # the preset's L, and L/R = h/100
def test_voltage_mode_locked_rotor_equals_analytic_current(drive_fmu, L_over_R_per_step):
    """Catches a voltage-mode drive whose locked-rotor current is not the RL circuit's (with saturation)."""
    R = motor1.R
    L = motor1.L if L_over_R_per_step is None else R * T * L_over_R_per_step
    params = {"mode": "voltage"} if L_over_R_per_step is None else {"mode": "voltage", "L": L}
    fmu = FmuInstance(drive_fmu, params)
    commanded = [3.0] * 7 + [11.0] * 5 + [30.0] * 9 + [5.0] * 13 + [17.0] * 6   # 30 V saturates at 24
    applied = [min(v, 24.0) for v in commanded]
    switches = [k * T for k in range(len(applied))]
    for k, v_ref in enumerate(commanded):
        fmu.step(T, v_ref=v_ref, omega=0.0, i_ref=123.0, i_hat=-7.0)     # current inputs ignored
        assert fmu.get("v") == applied[k]
        expected = analytic_locked_current((k + 1) * T, switches, applied, R, L)
        assert fmu.get("i") == pytest.approx(expected, rel=1e-9, abs=0.0), k
        assert fmu.get("tau") == pytest.approx(motor1.kt * expected, rel=1e-9, abs=0.0)
    fmu.close()


def test_explicit_euler_blows_up_when_L_over_R_is_100x_shorter_than_the_step(drive_fmu):
    """Documented property: Euler's factor 1 - hR/L = -99 there; 'exact' stays at v/R."""
    L = motor1.R * T / 100
    euler = FmuInstance(drive_fmu, {"mode": "voltage", "L": L, "method": "euler"})
    exact = FmuInstance(drive_fmu, {"mode": "voltage", "L": L})
    for _ in range(10):
        euler.step(T, v_ref=1.0)
        exact.step(T, v_ref=1.0)
    assert abs(euler.get("i")) > 1e15
    assert exact.get("i") == pytest.approx(1.0 / motor1.R, rel=1e-12)
    euler.close()
    exact.close()


# --- current mode: the FMU is motor.Drive --------------------------------------------------------------

@pytest.mark.parametrize("fmu_parameters, h", [
    ({}, T),
    ({"preset": "motor2", "R": 0.9, "L": 1e-3, "kt": 0.06, "ke": 0.055, "b": 1e-4, "mu": 0.03, "v_max": 12.0,
      "omega_eps": 0.2, "J_design": 2e-4, "omega0": 20.0, "i0": 0.3}, T),
    ({"method": "euler", "omega0": -5.0}, T / 4),
])
def test_current_mode_equals_in_process_drive_to_the_last_bit(drive_fmu, fmu_parameters, h):
    """Catches a drive FMU that differs from the in-process drive by a bit for any parameter set."""
    p = dict(fmu_parameters)
    params = get_motor_preset(p.pop("preset", "motor1"))
    rename = {"J_design": "J_rotor"}
    changes = {rename.get(k, k): p.pop(k) for k in list(p)
               if k in ("R", "L", "kt", "ke", "b", "mu", "v_max", "omega_eps", "J_design")}
    drive = Drive(params.with_(**changes), mode="current", method=p.pop("method", "exact"))
    omega0 = p.pop("omega0", 0.0)
    drive.start(omega0, p.pop("i0", 0.0))
    fmu = FmuInstance(drive_fmu, fmu_parameters)
    assert (fmu.get("v"), fmu.get("i"), fmu.get("tau")) == (drive.v, drive.i, drive.torque(omega0))
    rng = np.random.default_rng(7)
    for k in range(300):
        i_ref, omega, i_hat = rng.uniform(-3, 3), rng.uniform(-60, 60), rng.uniform(-3, 3)
        expected = drive.step(i_ref, 99.0, omega, i_hat, h)
        fmu.step(h, i_ref=i_ref, v_ref=99.0, omega=omega, i_hat=i_hat)
        assert tuple(fmu.get(n) for n in DRIVE_OUTPUTS) == expected, k
    assert fmu.get("error") == ""
    fmu.close()


@pytest.mark.parametrize("kind", ["static", "dynamic"])
def test_observer_fmu_equals_in_process_observer(observer_fmu, kind):
    """Catches an observer FMU that differs from the in-process observer or ignores its start values."""
    params = motor1.with_(R=1.3, ke=0.06, L=1e-3)
    obs = CurrentObserver(params, kind)
    obs.reset(0.25, 3.0)
    fmu = FmuInstance(observer_fmu, {"R": 1.3, "ke": 0.06, "L": 1e-3, "kind": kind, "i0": 0.25, "omega0": 3.0})
    assert fmu.get("i_hat") == 0.25
    rng = np.random.default_rng(3)
    for _ in range(100):
        v, omega = rng.uniform(-24, 24), rng.uniform(-60, 60)
        fmu.step(T, v=v, omega=omega)
        assert fmu.get("i_hat") == obs.estimate(v, omega, T)
    if kind == "static":
        assert fmu.get("i_hat") == pytest.approx((v - 0.06 * omega) / 1.3, rel=1e-14)   # (7.20)
    fmu.close()


# --- a 1 A current step with the observer FMU in the loop -------------------------------------------------

def fmu_step(drive_fmu, observer_fmu, preset, kind, omega, n):
    """Master loop at 1 ms: drive.step (reads observer.i_hat) -> observer.step (drive's new v, the speed)."""
    drive = FmuInstance(drive_fmu, {"preset": preset, "omega0": omega}, "drive")
    obs = FmuInstance(observer_fmu, {"preset": preset, "kind": kind, "omega0": omega}, "observer")
    i = [drive.get("i")]
    for _ in range(n):
        drive.step(T, i_ref=1.0, omega=omega, i_hat=obs.get("i_hat"))
        obs.step(T, v=drive.get("v"), omega=omega)
        i.append(drive.get("i"))
    drive.close()
    obs.close()
    return np.array(i)


@pytest.mark.parametrize("kind", ["static", "dynamic"])
@pytest.mark.parametrize("omega", [0.0, 50.0])
@pytest.mark.parametrize("preset", ["motor1", "motor2"])
def test_current_step_with_observer_fmu_settles(drive_fmu, observer_fmu, preset, kind, omega):
    """Within 1 % from 20 ms on, peak under 2 A; the same numbers as the in-process loop."""
    i = fmu_step(drive_fmu, observer_fmu, preset, kind, omega, n=60)
    np.testing.assert_array_equal(i, current_step(get_motor_preset(preset), kind, omega, n=60))
    assert i[0] == 0.0
    assert np.all(np.abs(i[20:] - 1.0) <= 0.01)
    assert i.max() < 2.0


# --- refusals ----------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["i_ref", "v_ref", "omega", "i_hat"])
def test_nan_drive_input_is_refused_and_outputs_stay(drive_fmu, name):
    """Catches a drive FMU accepting NaN or moving its outputs on a refused step."""
    fmu = FmuInstance(drive_fmu, {"omega0": 10.0})
    fmu.step(T, i_ref=0.5, omega=10.0)
    before = [fmu.get(n) for n in DRIVE_OUTPUTS]
    message = fmu.refused_step(T, **{name: float("nan")})
    assert f"{name} must be a finite number, got nan" in message and "t = 0.001" in message
    assert any(f"{name} must be a finite number, got nan" in m and "t = 0.001" in m for m in fmu.messages)
    assert [fmu.get(n) for n in DRIVE_OUTPUTS] == before and all(map(math.isfinite, before))
    fmu.close()


@pytest.mark.parametrize("name", ["v", "omega"])
def test_nan_observer_input_is_refused(observer_fmu, name):
    """Catches an observer FMU accepting inf or moving i_hat on a refused step."""
    fmu = FmuInstance(observer_fmu)
    fmu.step(T, v=2.0, omega=1.0)
    before = fmu.get("i_hat")
    message = fmu.refused_step(T, **{name: float("inf")})
    assert f"{name} must be a finite number, got inf" in message and "t = 0.001" in message
    assert any(message in m for m in fmu.messages)
    assert fmu.get("i_hat") == before and math.isfinite(before)
    fmu.close()


@pytest.mark.parametrize("parameters, expected", [
    ({"R": -0.5}, "parameter R = -0.5 is negative"),
    ({"L": -2e-3}, "parameter L = -0.002 is negative"),
    ({"R": 0.0}, "parameter R must be > 0, got 0.0"),
    ({"J_design": 0.0}, "parameter J_design must be > 0, got 0.0"),
    ({"mode": "torque"}, "mode must be one of 'current', 'voltage'; got 'torque'"),
    ({"preset": "motor3"}, "unknown motor preset 'motor3'"),
    ({"method": "rk4"}, "method must be one of 'exact', 'euler', 'quasi_static'; got 'rk4'"),
    ({"T": -1e-3}, "T must be > 0, got -0.001"),
    ({"omega0": float("nan")}, "omega0 must be a finite number, got nan"),
])
def test_bad_drive_parameters_are_refused_with_their_name(drive_fmu, parameters, expected):
    """Catches a drive FMU accepting a bad parameter, or refusing it without its name in the log."""
    fmu = FmuInstance(drive_fmu, parameters)
    message = fmu.refused_step(T, i_ref=1.0)
    assert expected in message
    assert any(expected in m and "step from t = 0 s refused" in m for m in fmu.messages)
    assert all(math.isfinite(fmu.get(n)) for n in DRIVE_OUTPUTS)
    fmu.refused_step(T, i_ref=1.0)                              # and every later step too
    fmu.close()


def test_current_mode_step_must_divide_the_controller_period(drive_fmu):
    """Catches a current-mode drive FMU accepting a step that does not divide T."""
    fmu = FmuInstance(drive_fmu)
    with pytest.raises(FMICallException) as info:
        fmu.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.3e-3)
    assert info.value.status != 4
    message = fmu.get("error")
    assert "does not divide the sample time T = 0.001 s" in message and "h = 0.0003 s" in message and "t = 0.0 s" in message
    fmu.close()


@pytest.mark.parametrize("parameters, expected", [
    ({"R": -0.5}, "parameter R = -0.5 is negative"),
    ({"ke": 0.0}, "parameter ke must be > 0, got 0.0"),
    ({"kind": "kalman"}, "kind must be one of 'static', 'dynamic'; got 'kalman'"),
    ({"preset": "x"}, "unknown motor preset 'x'"),
])
def test_bad_observer_parameters_are_refused_with_their_name(observer_fmu, parameters, expected):
    """Catches an observer FMU accepting a bad parameter, or refusing it without its name."""
    fmu = FmuInstance(observer_fmu, parameters)
    message = fmu.refused_step(T, v=1.0)
    assert expected in message
    assert any(expected in m and "step from t = 0 s refused" in m for m in fmu.messages)
    assert math.isfinite(fmu.get("i_hat"))
    fmu.close()


def test_drive_fmu_runs_in_a_process_without_parcosim(drive_fmu, tmp_path):
    """The FMU carries its own model code (motor/, fmus/slave/base.py), under its bundle's name."""
    from fmus.export.bundle import bundle_name

    script = (
        "import fmpy, sys\n"
        "r = fmpy.simulate_fmu(sys.argv[1], stop_time=0.02, step_size=1e-3,"
        " start_values={'mode': 'voltage', 'v_ref': 6.0, 'preset': 'motor2'})\n"
        "assert 'motor' not in sys.modules\n"
        f"print(sys.modules['{bundle_name()}.motor'].__file__)\n"
        "print(r['i'][-1])\n"
    )
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "PYTHONNOUSERSITE": "1"}
    done = subprocess.run([sys.executable, "-c", script, str(drive_fmu)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    module_file, i_end = done.stdout.split()[-2:]
    assert f"/resources/{bundle_name()}/motor/" in module_file
    assert not module_file.startswith(str(ROOT))
    assert float(i_end) == pytest.approx(6.0 / 0.829, rel=1e-9)
