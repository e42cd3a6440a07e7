"""The Trajectory, Derivator and PositionController FMUs through fmpy: validation, agreement
with the thesis' formulas and the in-process controller, refusals of bad input."""
import math

import numpy as np
import pytest
from fmpy.validation import validate_fmu

from controller.position import PositionController as InProcess
from controller.strategies import get_strategy
from plant import fivebar, get_preset
from tests.support.fmi_support import FmuInstance

NAMES = ("Trajectory", "Derivator", "PositionController")
SMALL_GRID = {"grid_step": 0.01, "x_min": -0.02, "x_max": 0.04, "y_min": 0.12, "y_max": 0.18, "cache": False}


@pytest.mark.parametrize("name", NAMES)
def test_fmpy_validate_finds_no_problem(built_fmus, name):
    """Catches a Trajectory, Derivator or PositionController FMU that fmpy's validation rejects."""
    assert validate_fmu(str(built_fmus[name])) == []


def thesis_reference(kind, t):
    """The thesis' formulas written out: (7.18) and (7.23); (7.27) on the first side of the triangle."""
    w = 2 * math.pi
    if kind == "thesis_circle":
        return (0.07 * math.cos(w * t), 0.17 + 0.07 * math.sin(w * t), -0.07 * w * math.sin(w * t),
                0.07 * w * math.cos(w * t), -0.07 * w * w * math.cos(w * t), -0.07 * w * w * math.sin(w * t))
    if kind == "circle":
        if t > 8.0:
            t = 8.0
            return (-0.05 * math.sin(w * t), 0.158 - 0.05 * math.cos(w * t), 0, 0, 0, 0)
        return (-0.05 * math.sin(w * t), 0.158 - 0.05 * math.cos(w * t), -0.05 * w * math.cos(w * t),
                0.05 * w * math.sin(w * t), 0.05 * w * w * math.sin(w * t), 0.05 * w * w * math.cos(w * t))
    tau = t / 0.75
    s = 35 * tau ** 4 - 84 * tau ** 5 + 70 * tau ** 6 - 20 * tau ** 7
    ds = (140 * tau ** 3 - 420 * tau ** 4 + 420 * tau ** 5 - 140 * tau ** 6) / 0.75
    dds = (420 * tau ** 2 - 1680 * tau ** 3 + 2100 * tau ** 4 - 840 * tau ** 5) / 0.75 ** 2
    dx, dy = 0.052, 0.150
    return (-0.002 + dx * s, 0.108 + dy * s, dx * ds, dy * ds, dx * dds, dy * dds)


@pytest.mark.parametrize("kind, steps", [("thesis_circle", 1200), ("circle", 300), ("triangle", 700)])
def test_trajectory_fmu_matches_the_thesis_formulas(built_fmus, kind, steps):
    """Catches a Trajectory FMU whose outputs differ from the thesis' formulas."""
    fmu = FmuInstance(built_fmus["Trajectory"], {"kind": kind})
    outputs = ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")
    scale = (1, 1, 1, 1, 1e-2, 1e-2)   # 1e-9 m on positions, relative on the derivatives
    got = [fmu.get(n) for n in outputs]
    assert np.allclose(got, thesis_reference(kind, 0.0), rtol=0, atol=1e-9)
    for k in range(steps):
        fmu.step(1e-3)
        expected = thesis_reference(kind, (k + 1) * 1e-3)   # outputs at the END of the step
        for name, value, ref, sc in zip(outputs, [fmu.get(n) for n in outputs], expected, scale):
            assert abs(value - ref) <= 1e-9 / sc, (name, k, value, ref)
    fmu.close()


def test_trajectory_fmu_holds_the_bench_start_by_default(built_fmus):
    """kind 'hold' with the default x_hold, y_hold holds x_1 = (-0.002, 0.108) m (7.28) at rest."""
    fmu = FmuInstance(built_fmus["Trajectory"], {"kind": "hold"})
    for _ in range(3):
        fmu.step(1e-3)
        assert [fmu.get(n) for n in ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d", "x_start", "y_start")] == \
            [-0.002, 0.108, 0.0, 0.0, 0.0, 0.0, -0.002, 0.108]
    fmu.close()


def test_trajectory_fmu_outputs_are_calculated_in_initialization_mode(built_fmus):
    """Through fmpy: read in Initialization Mode, x_start and the reference are the hold point
    just set (FMI 2.0, 4.2.4: outputs are initial="calculated"), as after initialisation."""
    fmu = FmuInstance(built_fmus["Trajectory"], {"kind": "hold", "x_hold": 0.01, "y_hold": 0.2}, initialise=False)
    outputs = ("x_start", "y_start", "x_d", "y_d")
    assert [fmu.get(n) for n in outputs] == [0.01, 0.2, 0.01, 0.2]
    fmu.initialise()
    assert [fmu.get(n) for n in outputs] == [0.01, 0.2, 0.01, 0.2]
    fmu.close()


def test_trajectory_fmu_refuses_unknown_kind(built_fmus):
    """Catches a Trajectory FMU running a default for an unknown kind."""
    fmu = FmuInstance(built_fmus["Trajectory"], {"kind": "square"})
    assert "unknown trajectory kind 'square'" in fmu.refused_step(1e-3)
    fmu.close()


@pytest.mark.parametrize("order", [1, 2])
def test_derivator_fmu_is_exact_on_ramps_and_parabolas(built_fmus, order):
    """Catches a Derivator FMU whose settled rates of ramps and parabolas are not exact."""
    fmu = FmuInstance(built_fmus["Derivator"], {"start_from_input": False, "q1_0": 0.3, "q2_0": -1.2})
    rate, acc = 0.7, -2.5
    for k in range(1500):
        t = k * 1e-3
        if order == 1:
            fmu.step(1e-3, q1=0.3 + rate * t, q2=-1.2 - rate * t)
        else:
            fmu.step(1e-3, q1=0.3 + 0.5 * acc * t * t, q2=-1.2 - 0.5 * acc * t * t)
    if order == 1:
        assert fmu.get("dq1") == pytest.approx(rate, abs=1e-9)
        assert fmu.get("dq2") == pytest.approx(-rate, abs=1e-9)
        assert abs(fmu.get("ddq1")) < 1e-7
    else:
        assert fmu.get("ddq1") == pytest.approx(acc, abs=1e-7)
        assert fmu.get("ddq2") == pytest.approx(-acc, abs=1e-7)
    fmu.close()


def test_derivator_fmu_refuses_nan_and_wrong_step(built_fmus):
    """Catches a Derivator FMU accepting NaN or a step other than its sample time."""
    fmu = FmuInstance(built_fmus["Derivator"])
    fmu.step(1e-3, q1=0.1, q2=0.2)
    assert abs(fmu.get("dq1")) < 1e-12    # starts at rest at the first input
    assert "input q1 = nan" in fmu.refused_step(1e-3, q1=float("nan"))
    fmu.close()
    fmu = FmuInstance(built_fmus["Derivator"])
    assert "does not divide the sample time T = 0.001 s" in fmu.refused_step(2e-3, q1=0.1, q2=0.2)
    fmu.close()


def controller_inputs(k):
    x, y = 0.01 + 0.002 * math.sin(k * 0.01), 0.15
    ang = fivebar.inverse_kinematics(get_preset("bench"), x, y)
    meas = (ang[0], ang[2], 0.3, -0.2, 1.0, 0.5)
    ref = (x + 0.001, y - 0.0005, 0.1, 0.2, -1.0, 0.5)
    return meas, ref


@pytest.mark.parametrize("strategy, model", [("TCMDx", "tabulated"), ("TCMDq", "exact"), ("PDMDq", "tabulated")])
def test_controller_fmu_equals_in_process(built_fmus, strategy, model):
    """Catches a PositionController FMU whose torques differ from the in-process controller."""
    params = dict(SMALL_GRID, strategy=strategy, model=model)
    fmu = FmuInstance(built_fmus["PositionController"], params)
    ctrl = InProcess(get_preset("bench"), get_strategy(strategy), model=model, grid_step=0.01,
                     extent=(-0.02, 0.04, 0.12, 0.18), cache=False)
    names = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")
    for k in range(20):
        meas, ref = controller_inputs(k)
        fmu.step(1e-3, **dict(zip(names, meas + ref)))
        expected = ctrl.step(k * 1e-3, *meas, *ref, 1e-3)
        assert [fmu.get(n) for n in ("tau1", "tau2", "i_ref1", "i_ref2")] == list(expected)
    fmu.close()


def test_controller_fmu_refuses_bad_input(built_fmus):
    """Catches a PositionController FMU accepting a NaN input or naming the wrong one."""
    meas, ref = controller_inputs(0)
    names = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")
    good = dict(zip(names, meas + ref))
    fmu = FmuInstance(built_fmus["PositionController"], {"strategy": "PDx"})
    fmu.step(1e-3, **good)
    message = fmu.refused_step(1e-3, **dict(good, dq2=float("nan")))
    assert "input dq2 = nan at t = 0.001 s" in message
    assert any("dq2 = nan" in m for m in fmu.messages)
    fmu.close()
    fmu = FmuInstance(built_fmus["PositionController"], {"strategy": "PDq"})
    message = fmu.refused_step(1e-3, **dict(good, x_d=0.4))
    assert "reference (x_d, y_d) = (0.4, 0.1495) m at t = 0 s is outside the workspace" in message
    fmu.close()
    fmu = FmuInstance(built_fmus["PositionController"], {"strategy": "PID"})
    message = fmu.refused_step(1e-3, **good)
    assert "strategy = 'PID' is unknown" in message
    fmu.close()
    fmu = FmuInstance(built_fmus["PositionController"], {"strategy": "TCx", "table_fallback": False, **SMALL_GRID})
    ang = fivebar.inverse_kinematics(get_preset("bench"), 0.0, 0.25)   # reachable, but off the small table
    message = fmu.refused_step(1e-3, **dict(good, q1=ang[0], q2=ang[2], x_d=0.0, y_d=0.25))
    assert "outside the tabulated region" in message and "t = 0 s" in message
    fmu.close()


@pytest.mark.parametrize("model, parameters, message", [
    ("Trajectory", {"kind": "circle", "frequency": 0.0}, "parameter frequency = 0.0 Hz must be > 0"),
    ("Derivator", {"fc_vel": 500.0}, "parameter fc_vel = 500.0 Hz must be below 1/(2T) = 500 Hz"),
    ("PositionController", {"T": 5e-10}, "parameter T = 5e-10 s must be >= 1e-09 s"),
])
def test_parameters_on_the_edge_are_refused(built_fmus, model, parameters, message):
    """The bounds themselves: a circle at 0 Hz does not move, a filter at the Nyquist
    frequency 1/(2T) (T = 1 ms) has no discrete counterpart, a sample time below the
    shortest step cannot be taken."""
    fmu = FmuInstance(built_fmus[model], parameters)
    assert message in fmu.refused_step(1e-3)
