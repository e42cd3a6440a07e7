"""Each native FMU equals its pythonfmu twin (issue 28, item 3).

The same script of FMI calls (parameters, reads in Initialization Mode, steps with varied
inputs, a refused step size and its repeat, FMU state get/set and serialise/deserialise,
a refused input, a refused set, terminate) runs through fmpy on both; every call's status
and logged messages must be equal, and every output within 1e-12 of its peak magnitude over
the run.  Wrong code it catches: an adapter reading a wrong slot or parameter, a state
that does not restore the run, a message worded or formatted differently (repr, .6g), a
refusal with another status.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import pytest

from controller.balance import BalanceSettings
from tests.support.fmu_calls import Driver

pytestmark = [pytest.mark.fmu]

BALANCE_T = BalanceSettings().T
#: The bench twin's drive options (scenarios/twin.py): LuGre friction with stiction, PWM, current noise and offset.
DRIVE_TWIN = {"friction": "lugre", "mu": 0.06, "mu_s": 0.08, "pwm_counts": 1000, "current_offset": 0.05,
              "current_noise": 0.1, "noise_seed": 7, "noise_instance": 2}


def _controller_inputs():
    """The circle's references, and measured angles of a pose beside them (their derivatives
    by central differences) that leaves the table (x > x_max = 0.12 m) from step 90 to 140:
    the tabulated model falls back to the exact one there, or refuses without
    ``table_fallback``."""
    from controller.kinematics import Kinematics
    from controller.trajectories import get_trajectory
    from plant import get_preset

    kin, circle = Kinematics(get_preset("bench")), get_trajectory("circle")

    def pose(k, t):
        away = 0.17 * math.sin(math.pi * (k - 90) / 50) ** 2 if 90 <= k <= 140 else 0.0
        r = circle(t)
        angles = kin.inverse(r.x + 0.002 * math.sin(11.0 * t) + away, r.y - 0.001 * math.cos(7.0 * t))
        return angles[0], angles[2]

    def inputs(k, t):
        d = 1e-4
        (a1, a2), (b1, b2), (c1, c2) = pose(k, t), pose(k, t + d), pose(k, t + 2 * d)
        r = circle(t)
        return {"q1": b1, "q2": b2, "dq1": (c1 - a1) / (2 * d), "dq2": (c2 - a2) / (2 * d),
                "ddq1": (c1 - 2 * b1 + a1) / d ** 2, "ddq2": (c2 - 2 * b2 + a2) / d ** 2,
                "x_d": r.x, "y_d": r.y, "dx_d": r.dx, "dy_d": r.dy, "ddx_d": r.ddx, "ddy_d": r.ddy}
    return inputs


#: Every strategy of the slave (the thesis' eight, seed 001's two), the triangle's joint-space
#: table, the adaptive gain, the exact model, the overrides, the delay, the table's refusal.
CONTROLLER_PARAMETERS = (
    [{}] + [{"strategy": s} for s in ("PDq", "PDx", "TCq", "TCx", "PDMDq", "PDMDx", "TCMDq", "TCMDx", "SMCq", "SMCx")]
    + [{"strategy": "PDMDq", "trajectory": "triangle"}, {"strategy": "TCMDq", "trajectory": "hold"},
       {"strategy": "TCMDx", "gamma1": 40.0, "gamma2": 15.0}, {"strategy": "PDMDq", "gamma1": 30.0},
       {"strategy": "TCx", "model": "exact"}, {"strategy": "TCMDq", "model": "exact", "delay_steps": 2},
       {"strategy": "SMCx", "model": "exact"}, {"strategy": "TCMDx", "delay_steps": 1, "kt1": 0.05},
       {"strategy": "PDx", "lam": 40.0, "m_star": 0.3, "phi": 3.0, "k1": 20.0, "k2": 5.0, "preset": "thesis_sim"},
       {"table_fallback": False}, {"strategy": "PDx", "delay_compensation": 2, "velocity_delay_compensation": 3},
       {"strategy": "TCMDq", "model": "exact", "delay_compensation": 1, "delay_steps": 1},
       # refusals at initialisation, in the slave's order
       {"strategy": "PD"}, {"trajectory": "square"}, {"T": 0.0}, {"lam": math.nan}, {"phi": 2e6},
       {"gamma2": -1.0}, {"kt1": -2.0}, {"kt2": 0.0}, {"kt1": 1e-13}, {"grid_step": 0.0},
       {"y_min": 0.3}, {"grid_step": 1e-4}, {"delay_steps": 101}, {"delay_compensation": 9},
       {"velocity_delay_compensation": -1}, {"preset": "nope"},
       {"counter_mass1": -0.1}, {"counter_mass2": 1e-4}, {"lam": -2.0}, {"strategy": "PDx", "m_star": 0.0},
       {"k2": -3.0}, {"model": "lookup"}, {"model_error": -1.0}])


@dataclass
class Scenario:
    """A model's run: its step size, inputs at step k (time t), parameter sets to try, an input
    to make NaN ("" for none), a fixed parameter and a value to set after initialisation."""

    h: float
    inputs: Callable
    parameters: list = field(default_factory=lambda: [{}])
    bad_input: str = ""
    fixed: tuple = ()
    steps: int = 240


SCENARIOS = {
    "Derivator": Scenario(
        1e-3, lambda k, t: {"q1": 0.4 * math.sin(7.0 * t) + 0.1, "q2": -0.3 + 2.0 * t * t},
        [{}, {"start_from_input": False, "q1_0": 0.25, "q2_0": -0.5}, {"T": -1.0}, {"fc_vel": 600.0}],
        "q2", ("fc_acc", 1.5)),
    "BalanceController": Scenario(
        BALANCE_T, lambda k, t: {"enc_l": 0.3 * math.sin(3.0 * t), "enc_r": 0.2 * t, "gyro": 0.05 * math.cos(9.0 * t)},
        [{}, {"route": "forward_turn"}, {"route": "sideways"}, {"T": 0.0}, {"v_battery": math.nan}],
        "gyro", ("yaw", False), steps=200),
    "WheeledPendulum": Scenario(
        1e-3, lambda k, t: {"tau_l": 0.02 * math.sin(5.0 * t), "tau_r": -0.01, "tau_d": 0.003 * math.cos(2.0 * t)},
        [{}, {"model": "seed", "yaw": False, "psi0": 0.05, "push_torque": 0.05, "push_start": 0.01,
              "push_duration": 0.02, "substeps": 3, "encoder_counts": 500},
         {"psi0": 1.2, "dpsi0": 3.0}, {"model": "lagrange"}, {"R": 0.0}, {"M": math.nan}, {"substeps": 0},
         {"yaw": False, "dphi0": 0.5}, {"psi0": 2.0}, {"push_duration": -1.0}, {"L": 1e-13}],
        "tau_r", ("g", 1.6), steps=200),
    "CurrentObserver": Scenario(
        5e-4, lambda k, t: {"v": 12.0 * math.sin(40.0 * t) + 0.5, "omega": 30.0 * math.cos(15.0 * t)},
        [{}, {"kind": "dynamic"}, {"kind": "dynamic", "preset": "motor2", "R": 1.3, "L": 0.0},
         {"preset": "nope"}, {"R": -2.0}, {"ke": math.nan}, {"L": math.inf}, {"kind": "both"}, {"T": 0.0}],
        "omega", ("R", 1.5)),
    "DCMotorDrive": Scenario(
        1e-3, lambda k, t: {"i_ref": 0.5 * math.sin(20.0 * t) + 0.1, "v_ref": 6.0 * math.sin(30.0 * t) + 1.0,
                            "omega": 30.0 * math.cos(15.0 * t), "i_hat": 0.4 * math.sin(20.0 * t - 0.1)},
        [{}, {**DRIVE_TWIN, "torque_output": "mean", "omega0": 3.0, "i0": 0.2},
         {"mode": "voltage", "preset": "motor2", "method": "quasi_static", "L": 0.0, "R": 2.0},
         {"mode": "voltage", "preset": "seed000"}, {"mode": "voltage", "method": "euler", "L": 2e-6},
         {"internal_observer": True}, {"internal_observer": True, "observer_kind": "dynamic", "omega0": -2.0},
         {"method": "euler", "torque_output": "mean"}, {"preset": "motor2", "sample_phase": 0},
         {"R": -2.0}, {"preset": "nope"}, {"T": 0.0}, {"T": 1e-10}, {"friction": "x"}, {**DRIVE_TWIN, "mu_s": 0.01},
         {"friction": "lugre", "preset": "seed000", "mode": "voltage"},
         {"mode": "voltage", "method": "euler", "L": 0.0},
         {"internal_observer": True, "mode": "voltage"}, {"observer_kind": "both"}, {"pwm_counts": -1},
         {"noise_seed": -3}, {"sample_phase": -1}, {"current_noise": -0.1}, {"current_offset": math.nan},
         {"torque_output": "x"}, {"mode": "x"}, {"method": "x"}, {"J_design": math.nan}, {"kt": 1e-13},
         {"R_design": -5.0}, {"L_design": 2e6}, {"omega0": math.inf}, {"i0": 2e6}, {"v_max": 0.0},
         {"preset": "seed000"}],
        "omega", ("R", 1.5)),
    "PositionController": Scenario(1e-3, _controller_inputs(), CONTROLLER_PARAMETERS, "q1", ("strategy", "PDx")),
    "Trajectory": Scenario(
        1e-3, lambda k, t: {}, [{}, {"kind": "triangle"}, {"kind": "thesis_circle"}, {"kind": "hold"},
                                {"kind": "square"}, {"cycles": 0}, {"side_time": float("inf")}],
        "", ("kind", "hold"), steps=300),
    "FiveBarPlant": Scenario(
        1e-3, lambda k, t: {"tau1": 0.02 * math.sin(9.0 * t), "tau2": -0.015 + 0.01 * math.cos(4.0 * t)},
        [{}, {"preset": "bench", "x0": -0.002, "y0": 0.108},
         # chain overrides, counter-masses, gravity, point-mass links, an encoder offset, substeps
         {"preset": "bench", "chain1_l2": 0.17, "chain2_lg2": 0.07, "counter_mass1": 0.4, "counter_mass2": 0.25,
          "gravity_y": -9.81, "link_inertias": False, "encoder_offset1": 0.001, "substeps": 3, "J_rotor2": 2e-6},
         {"project": True, "m0": 0.05, "gravity_x": 1.0, "encoder_counts": 4000, "baumgarte": 50.0},
         # light point-mass links: the run diverges
         {f"chain{k}_{f}": 1e-4 if f[0] == "m" else 0.0 for k in (1, 2) for f in ("m1", "m2", "Jz1", "Jz2")},
         {"x0": 0.0, "y0": 0.2653},   # a singular pose reached
         {"baumgarte": 5000.0}, {"preset": "nope"}, {"l0": 2e6}, {"l0": 1e-13}, {"l0": 0.0}, {"l0": 0.3},
         {"chain2_m1": -2.0}, {"chain1_l1": 0.0}, {"chain1_lg1": math.nan}, {"counter_mass1": 1e-6},
         {"counter_mass2": -1.0}, {"m0": 0.1, "counter_mass1": 0.2}, {"x0": 1.0}, {"x0": math.nan},
         {"x0": 0.0, "y0": 0.265329}, {"substeps": 0}, {"encoder_counts": 0}, {"rtol": 0.0}, {"J_rotor1": -2.0},
         {"method": "euler"}, {"kernel": "slow"}],
        "tau2", ("x0", 0.05)),
    "ActuatedFiveBarPlant": Scenario(
        1e-3, lambda k, t: {"i_ref1": 0.3 * math.sin(9.0 * t), "i_ref2": -0.2 + 0.2 * math.cos(4.0 * t),
                            "i_hat1": 0.25 * math.sin(9.0 * t - 0.1), "i_hat2": -0.2 + 0.15 * math.cos(4.0 * t),
                            "v_ref1": math.sin(5.0 * t), "v_ref2": -0.5},
        [{}, {"preset": "bench", "x0": -0.002, "y0": 0.108, "friction1": "lugre", "friction2": "lugre"},
         {"mode": "voltage", "substeps": 3, "counter_mass1": 0.3, "gravity_y": -9.81, "chain2_l1": 0.13,
          "pwm_counts1": 200, "current_noise2": 0.01, "noise_seed2": 4, "encoder_offset2": 0.002},
         # the bench's imperfections; the run reaches a singular pose
         {"current_offset1": 0.05, "pwm_counts2": 100, "current_noise1": 0.02, "noise_seed1": 7, "noise_instance1": 1,
          "friction2": "lugre", "link_inertias": False},
         {"x0": 0.0, "y0": 0.2653, "mode": "voltage"}, {"baumgarte": 5000.0},
         # the projection (the twin's composition around the kernels), one with LuGre and m0
         {"project": True}, {"project": True, "mode": "voltage", "friction1": "lugre", "preset": "bench",
                             "x0": -0.002, "y0": 0.108, "m0": 0.02},
         {"T": 2e6}, {"T": 1e-10}, {"L1": 0.0}, {"L2": 1e-13}, {"preset1": "nope"}, {"R2": -2.0},
         {"friction1": "stick"}, {"sample_phase": 1}, {"preset": "nope"}, {"substeps": 0}, {"x0": 1.0},
         {"mu_s2": 0.0, "friction2": "lugre"}, {"mode": "both"}, {"counter_mass2": 1e-6}],
        "i_hat2", ("x0", 0.05)),
}


def outputs(driver) -> list:
    """The outputs (the refusal's record ``refusal`` among them, compared byte for byte)."""
    return [v.name for v in driver.md.modelVariables if v.causality == "output"]


def script(scenario: Scenario, parameters: dict, outs: list, real_output: str) -> list:
    h, steps = scenario.h, scenario.steps
    calls = [("set", parameters), ("get", outs), ("set", {real_output: 1.0}),
             ("setup", 0.0, 10.0), ("enter",), ("get", outs), ("exit",), ("set", dict([scenario.fixed]))]
    t = 0.0
    for k in range(steps):
        calls += [("set", scenario.inputs(k, t)), ("step", t, h), ("get", outs)]
        t = (k + 1) * h
        if k == steps // 3:
            calls += [("getstate", "s"), ("serialize", "s", "b")]
            mark = t
    calls += [("step", t, 2.5 * h), ("get", outs), ("step", t, h)]   # refused, then refused again
    calls += [("setstate", "s"), ("get", outs)]
    for k in range(steps // 3 + 1, steps // 3 + 20):
        calls += [("set", scenario.inputs(k, mark)), ("step", mark, h), ("get", outs)]
        mark = (k + 1) * h
    calls += [("deserialize", "b", "d"), ("setstate", "d"), ("get", outs)]
    if scenario.bad_input:
        calls += [("set", {scenario.bad_input: math.nan})]
    calls += [("step", (steps // 3 + 1) * h, h), ("get", outs)]
    calls += [("terminate",), ("step", 0.0, h)]
    return calls


def run(driver: Driver, calls: list):
    trace = []
    for call in calls:
        if call[0] == "serialize":   # (serialize, state key, bytes key)
            step = driver.call("bytes", call[2], driver.fmu.serializeFMUstate(driver.states[call[1]]))
        elif call[0] == "deserialize":
            step = driver.call("bytes", call[2], driver.fmu.deSerializeFMUstate(driver.states[call[1]]))
        else:
            step = driver.call(*call)
        trace.append(step)
    return trace


def assert_same(twin_trace, native_trace, outs, tolerance=1e-12):
    reads = [s.result for s in twin_trace if s.call[0] == "get"]
    peak = {name: max(abs(r[k]) for r in reads if isinstance(r[k], float)) for k, name in enumerate(outs)
            if isinstance(reads[0][k], float)}
    for twin, native in zip(twin_trace, native_trace, strict=True):
        assert native.status == twin.status, (twin.call, twin.messages, native.messages)
        assert native.messages == twin.messages, twin.call
        if twin.call[0] != "get":
            continue
        for name, a, b in zip(outs, twin.result, native.result):
            if name in peak:
                assert abs(a - b) <= tolerance * peak[name], (twin.call, name, a, b)
            else:
                assert a == b, (twin.call, name)


def compare(twin_path, native_path, scenario: Scenario, parameters: dict, extra=lambda outs: [],
            tolerance=1e-12) -> list:
    """Run the script (and ``extra(outs)`` before its terminate) on both, every output within
    ``tolerance`` of its peak; return the twin's trace."""
    twin, native = Driver(twin_path), Driver(native_path)
    outs = outputs(twin)
    assert outputs(native) == outs
    real = next(v.name for v in twin.md.modelVariables if v.causality == "output" and v.type == "Real")
    calls = script(scenario, parameters, outs, real)
    end = calls.index(("terminate",))
    calls[end:end] = extra(outs)
    twin_trace, native_trace = run(twin, calls), run(native, calls)
    statuses = [s.status for s in twin_trace]
    assert statuses.count(2) >= 2 and statuses.count(3) >= 2   # the script does reach the refusals
    assert_same(twin_trace, native_trace, outs, tolerance)
    twin.close()
    native.close()
    return twin_trace


@pytest.mark.parametrize("model", sorted(SCENARIOS))
def test_native_fmu_equals_its_pythonfmu_twin(model, native_fmus, twin_fmus):
    """Catches a native FMU whose C stepping differs from its pythonfmu twin's in any scenario and
    parameter set."""
    scenario = SCENARIOS[model]
    for parameters in scenario.parameters:
        compare(twin_fmus[model], native_fmus[model], scenario, parameters)


#: The sampled models (fmus/slave/sampling.py; the drive in current mode), run again with steps h = T / 4.
SAMPLED = ("ActuatedFiveBarPlant", "BalanceController", "CurrentObserver", "DCMotorDrive", "Derivator",
           "PositionController")


@pytest.mark.parametrize("model", SAMPLED)
def test_substepped_native_fmu_equals_its_pythonfmu_twin(model, native_fmus, twin_fmus):
    """h = T / 4 sampled on sub-step 2 (the state is taken and restored mid-period, a step
    changing h mid-period is refused), and sample phases out of [0, 4) refused at the first
    step.  Wrong code it catches: a native counter that is not FMU state, samples on another
    sub-step, advances on a refused step, or words a refusal otherwise."""
    base = SCENARIOS[model]
    T = float(Driver(twin_fmus[model]).variables["T"].start)
    h = T / 4
    scenario = Scenario(h, base.inputs, bad_input=base.bad_input, fixed=base.fixed, steps=base.steps)
    mark = (scenario.steps // 3 + 1) * h
    assert round(mark / h) % 4 != 0   # the state is taken mid-period

    def period_change(outs):
        return [("setstate", "s"), ("step", mark, h / 2), ("get", outs),
                ("setstate", "s"), ("step", mark, h), ("get", outs)]

    for parameters in ({"sample_phase": 2}, {**base.parameters[1], "sample_phase": 3}, {"sample_phase": 4},
                       {"sample_phase": -1}):
        trace = compare(twin_fmus[model], native_fmus[model], scenario, parameters, period_change)
        said = " ".join(m[2] for s in trace for m in s.messages)
        if parameters["sample_phase"] in (2, 3):
            assert "changes the step within a sample period" in said and "does not divide" in said
        else:   # motor.Drive refuses a negative phase at initialisation already
            phase = parameters["sample_phase"]
            assert (f"parameter sample_phase = {phase} must be a whole number" in said or
                    model in ("ActuatedFiveBarPlant", "DCMotorDrive") and phase == -1
                    and "sample_phase must be a whole number" in said)


@pytest.mark.parametrize("model", SAMPLED)
def test_sampled_native_fmu_declares_its_period(model, native_fmus, twin_fmus):
    """As the twin: no variable step size, DefaultExperiment stepSize T, the sample_phase parameter."""
    twin, native = Driver(twin_fmus[model]).md, Driver(native_fmus[model]).md
    assert native.coSimulation.canHandleVariableCommunicationStepSize is False
    assert twin.coSimulation.canHandleVariableCommunicationStepSize is False
    assert float(native.defaultExperiment.stepSize) == float(twin.defaultExperiment.stepSize)
    phase = {v.name: v for v in native.modelVariables}["sample_phase"]
    assert (phase.type, phase.causality, phase.start) == ("Integer", "parameter", "0")


#: A model, a parameter set the native FMU cannot honour (a design it does not carry, a setting
#: with no C), and what its refusal names.
UNBUILT = [
    ("Derivator", {"fc_vel": 50.0}, "fc_vel = 50.0 Hz"),
    ("BalanceController", {"yaw": False}, "parameter yaw = False: this native FMU carries the balance design"),
    ("Trajectory", {"kind": "circle", "cycles": 3}, "parameter cycles = 3: this native FMU carries the circle"),
    ("FiveBarPlant", {"method": "dopri5"}, "parameter method = 'dopri5': the native FiveBarPlant integrates with "
                                           "'rk4' only (dopri5 has no C implementation)"),
    ("FiveBarPlant", {"kernel": "general"}, "parameter kernel = 'general': the native FiveBarPlant computes with "
                                            "kernel 'fast' only (the general algorithm has no C implementation)"),
    ("ActuatedFiveBarPlant", {"method": "dopri5"}, "parameter method = 'dopri5': the native ActuatedFiveBarPlant "
                                                   "integrates with 'rk4' only"),
    ("DCMotorDrive", {"b": 0.0}, "b = 0.0, J_rotor = 0.0001469, T = 0.001: with b = 0 the plant's zero is z = 1, "
                                 "the controller's integrator, and appendix C's system is singular"),
    ("ActuatedFiveBarPlant", {"b2": 0.0}, "(set b2 or b_design2 > 0, or use the pythonfmu FMU)"),
]


@pytest.mark.parametrize("model, parameters, says", UNBUILT)
def test_parameters_the_native_fmu_cannot_honour_are_refused_by_name(model, parameters, says, native_fmus,
                                                                     twin_fmus):
    """The twin accepts them (it designs with scipy at initialisation, integrates with dopri5
    or the general algorithm in numpy); the native FMU refuses its initialisation naming the
    parameter and its value, and every step after it."""
    calls = [("set", parameters), ("setup", 0.0), ("enter",), ("exit",), ("step", 0.0, 1e-3), ("get", ["error"])]
    twin, native = Driver(twin_fmus[model]).run(calls), Driver(native_fmus[model]).run(calls)
    assert [s.status for s in twin] == [0] * 6 and twin[-1].result == [""]
    assert native[3].status == 0 and says in native[3].messages[0][2]
    assert native[4].status == 2 and says in native[-1].result[0]


def test_drive_in_voltage_mode_takes_any_step_as_its_twin(native_fmus, twin_fmus):
    """Voltage mode: steps of 0.37 ms (not dividing T) run the whole script as the twin's;
    current mode refuses them, as the twin, with its rule's words."""
    base = SCENARIOS["DCMotorDrive"]
    scenario = Scenario(3.7e-4, base.inputs, bad_input=base.bad_input, fixed=base.fixed)
    for parameters in ({"mode": "voltage", "torque_output": "mean"},
                       {"mode": "voltage", "friction": "lugre", "pwm_counts": 500, "omega0": 4.0}, {}):
        trace = compare(twin_fmus["DCMotorDrive"], native_fmus["DCMotorDrive"], scenario, parameters)
        said = " ".join(m[2] for s in trace for m in s.messages)
        steps = [s.status for s in trace if s.call[0] == "step"]
        if parameters:
            assert steps[:base.steps] == [0] * base.steps
        else:
            assert "does not divide the sample time T = 0.001 s; DCMotorDrive accepts in current mode" in said


def test_controller_falls_back_to_the_exact_model_off_the_table(native_fmus, twin_fmus):
    """The script's measured pose leaves the table (x > 0.12 m): both count the samples that
    used the exact model (``model_fallbacks``) alike, or refuse the step naming the pose
    without ``table_fallback``.  Wrong code it catches: a fallback not taken, not counted, or
    counted on a refused sample."""
    scenario = SCENARIOS["PositionController"]
    outs = outputs(Driver(twin_fmus["PositionController"]))
    trace = compare(twin_fmus["PositionController"], native_fmus["PositionController"], scenario, {})
    assert max(s.result[outs.index("model_fallbacks")] for s in trace if s.call[0] == "get") > 5
    trace = compare(twin_fmus["PositionController"], native_fmus["PositionController"], scenario,
                    {"table_fallback": False})
    assert any("is outside the tabulated region x in [-0.12, 0.12]" in m[2] for s in trace for m in s.messages)


def test_substepped_controller_equals_its_twin_for_every_strategy(native_fmus, twin_fmus):
    """h = T / 4 for each strategy (and the exact model, the adaptive gain, the delay queue),
    sampling on sub-steps 1, 2, 3 in turn, the state taken and restored mid-period.  Wrong
    code it catches: a strategy whose law, model or queue advances on a held sub-step."""
    base = SCENARIOS["PositionController"]
    scenario = Scenario(1e-3 / 4, base.inputs, bad_input=base.bad_input, fixed=base.fixed)
    runs = [{"strategy": s} for s in ("PDq", "PDx", "TCq", "TCx", "PDMDq", "PDMDx", "TCMDq", "TCMDx", "SMCq", "SMCx")]
    runs += [{"strategy": "TCMDx", "model": "exact", "gamma1": 40.0, "delay_steps": 2}]
    for k, parameters in enumerate(runs):
        compare(twin_fmus["PositionController"], native_fmus["PositionController"], scenario,
                {**parameters, "sample_phase": 1 + k % 3})
