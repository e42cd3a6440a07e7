"""The FiveBarPlant FMU through fmpy: validation, bit-identity with the
in-process model, and clean refusals of bad input."""
import math
import subprocess
import sys

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from fmus.slaves.parcosim_fivebarplant import OUTPUTS
from plant import IntegratorSettings, PlantSimulator, get_preset
from tests.support.fmi_support import FmuInstance


def torques(t):
    return 0.05 * math.sin(2 * math.pi * 3 * t), -0.04 * math.cos(2 * math.pi * 2 * t)


def test_fmpy_validate_finds_no_problem(built_fmus):
    """Catches a FiveBarPlant FMU that fmpy's validation rejects."""
    assert validate_fmu(str(built_fmus["FiveBarPlant"])) == []


def test_model_structure_declares_no_direct_feedthrough(built_fmus):
    """Catches a FiveBarPlant FMU declaring feedthrough (masters would see an algebraic loop)."""
    from fmpy import read_model_description
    md = read_model_description(str(built_fmus["FiveBarPlant"]))
    names = {o.variable.name for o in md.outputs}
    assert set(OUTPUTS) <= names
    assert all(o.dependencies == [] for o in md.outputs)
    assert {u.variable.name for u in md.initialUnknowns} == names


@pytest.mark.parametrize("preset, x0, y0", [("thesis_sim", 0.07, 0.17), ("bench", -0.002, 0.108)])
def test_fmu_equals_the_in_process_model_to_the_last_bit(built_fmus, preset, x0, y0):
    """Catches a FiveBarPlant FMU that differs from the in-process plant by a bit."""
    fmu = FmuInstance(built_fmus["FiveBarPlant"], {"preset": preset, "x0": x0, "y0": y0})
    sim = PlantSimulator(get_preset(preset), x0, y0)
    assert fmu.get("q1") == sim.outputs()["q1"]
    for k in range(300):
        tau1, tau2 = torques(k * 1e-3)
        fmu.step(1e-3, tau1=tau1, tau2=tau2)
        sim.step(tau1, tau2, 1e-3)
        expected = sim.outputs()
        for name in OUTPUTS:
            assert fmu.get(name) == expected[name], (name, k)
    fmu.close()


def test_integrator_parameters_reach_the_model(built_fmus):
    """Catches FMU integrator parameters (method, tolerances, Baumgarte, kernel) not reaching the plant."""
    settings = {"method": "dopri5", "rtol": 1e-11, "atol": 1e-14, "baumgarte": 5.0, "kernel": "general"}
    fmu = FmuInstance(built_fmus["FiveBarPlant"], settings)
    sim = PlantSimulator(get_preset("thesis_sim"), 0.07, 0.17, IntegratorSettings(**settings))
    for k in range(5):
        fmu.step(1e-3, tau1=0.05, tau2=-0.02)
        sim.step(0.05, -0.02, 1e-3)
    assert fmu.get("x") == sim.outputs()["x"]
    fmu.close()


def test_nan_torque_is_refused_and_outputs_stay_finite(built_fmus):
    """Catches a plant FMU accepting NaN torque or moving its outputs on a refused step."""
    fmu = FmuInstance(built_fmus["FiveBarPlant"])
    fmu.step(1e-3, tau1=0.01, tau2=0.0)
    x_before = fmu.get("x")
    message = fmu.refused_step(1e-3, tau1=float("nan"))
    assert "tau1 = nan" in message and "t = 0.001" in message
    assert any("tau1 = nan" in m for m in fmu.messages)
    assert fmu.get("x") == x_before and all(math.isfinite(fmu.get(n)) for n in OUTPUTS)
    fmu.close()


@pytest.mark.parametrize("parameters, expected", [
    ({"x0": 0.5}, "x0=0.5"),
    ({"preset": "nope"}, "unknown preset 'nope'"),
    ({"m0": -0.1}, "m0 must be >= 0, got -0.1"),
    ({"l0": 0.4}, "cannot close the loop"),
    ({"J_rotor1": -0.5}, "J_rotor1 = -0.5"),
    ({"method": "euler"}, "unknown integrator 'euler'"),
])
def test_bad_parameters_are_refused_with_their_name(built_fmus, parameters, expected):
    """Catches a plant FMU accepting a bad parameter, or refusing it without its name."""
    fmu = FmuInstance(built_fmus["FiveBarPlant"], parameters)
    assert expected in fmu.refused_step(1e-3, tau1=0.0)
    assert any(expected in m for m in fmu.messages)
    assert all(math.isfinite(fmu.get(n)) for n in OUTPUTS)
    fmu.close()


def test_singularity_during_a_step_is_refused_with_time(built_fmus):
    """Catches a plant FMU stepping through a singular pose or refusing without time."""
    fmu = FmuInstance(built_fmus["FiveBarPlant"])
    with pytest.raises(FMICallException):
        for _ in range(5000):
            fmu.step(1e-3, tau1=0.05, tau2=0.0)
    assert "singular pose reached at t = " in fmu.get("error")
    assert all(math.isfinite(fmu.get(n)) for n in OUTPUTS)
    fmu.close()


def test_two_fmus_in_one_process_do_not_interfere(built_fmus):
    """Catches two plant FMU instances sharing state (a module global)."""
    a = FmuInstance(built_fmus["FiveBarPlant"], {"preset": "bench", "x0": -0.002, "y0": 0.108}, "a")
    b = FmuInstance(built_fmus["FiveBarPlant"], {"preset": "thesis_sim"}, "b")
    for _ in range(10):
        a.step(1e-3, tau1=0.02, tau2=0.0)
        b.step(1e-3, tau1=0.0, tau2=0.0)
    assert b.get("x") == 0.07 and a.get("x") != -0.002
    a.close()
    b.close()


def test_fmu_runs_in_a_process_without_parcosim(built_fmus, tmp_path):
    """The FMU carries its own model code: a fresh interpreter that cannot import
    the project (cwd elsewhere, no path to it) still simulates it."""
    script = (
        "import fmpy, sys\n"
        "assert 'plant' not in sys.modules\n"
        f"r = fmpy.simulate_fmu({str(built_fmus['FiveBarPlant'])!r}, stop_time=0.01, step_size=1e-3,"
        " start_values={'tau1': 0.01})\n"
        "print(r['x'][-1])\n"
    )
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "PYTHONNOUSERSITE": "1"}
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert 0.069 < float(done.stdout.split()[-1]) < 0.071


@pytest.mark.parametrize("inside_a_system", [False, True], ids=["alone", "in_a_budget"])
@pytest.mark.parametrize("idle", [1, 2])
def test_idle_steps_hold_zero_torques_for_that_many_steps_then_the_inputs_again(idle, inside_a_system):
    """A model of the plant inside a controller (ChainCore's zero start) is made idle for
    ``idle`` steps: those steps are a twin's steps at zero torques, bit for bit, whatever its
    inputs say, then the count is spent and the inputs act again.  Catches the count not
    counting down (seed 4001's survivor [166], ``idle_steps += 1``: idle for ever), and the
    budgeted path (inside a system FMU) ignoring idleness."""
    import contextlib

    from fmus.slave import budget
    from tests.fmus.slave.test_extremes import make_slave

    model, twin = make_slave("FiveBarPlant"), make_slave("FiveBarPlant")
    h = 1e-3
    model.idle_steps = idle
    with budget.call_budget() if inside_a_system else contextlib.nullcontext():
        for k in range(idle + 2):
            model.tau1, model.tau2 = torques(k * h)
            twin.tau1, twin.tau2 = (0.0, 0.0) if k < idle else torques(k * h)
            assert model.do_step(k * h, h) is not False and twin.do_step(k * h, h) is not False
            assert model.idle_steps == max(idle - k - 1, 0)
            assert np.array_equal(model.sim.y, twin.sim.y), k
