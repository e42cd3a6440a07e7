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
from support.fmu_calls import Driver

BALANCE_T = BalanceSettings().T


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
    "Trajectory": Scenario(
        1e-3, lambda k, t: {}, [{}, {"kind": "triangle"}, {"kind": "thesis_circle"}, {"kind": "hold"},
                                {"kind": "square"}, {"cycles": 0}, {"side_time": float("inf")}],
        "", ("kind", "hold"), steps=300),
}


def outputs(driver) -> list:
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


def assert_same(twin_trace, native_trace, outs):
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
                assert abs(a - b) <= 1e-12 * peak[name], (twin.call, name, a, b)
            else:
                assert a == b, (twin.call, name)


def compare(twin_path, native_path, scenario: Scenario, parameters: dict, extra=lambda outs: []) -> list:
    """Run the script (and ``extra(outs)`` before its terminate) on both; return the twin's trace."""
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
    assert_same(twin_trace, native_trace, outs)
    twin.close()
    native.close()
    return twin_trace


@pytest.mark.parametrize("model", sorted(SCENARIOS))
def test_native_fmu_equals_its_pythonfmu_twin(model, native_fmus, twin_fmus):
    scenario = SCENARIOS[model]
    for parameters in scenario.parameters:
        compare(twin_fmus[model], native_fmus[model], scenario, parameters)


#: The sampled models (fmus/slave/sampling.py), run again with steps h = T / 4.
SAMPLED = ("BalanceController", "CurrentObserver", "Derivator")


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
        else:
            assert f"parameter sample_phase = {parameters['sample_phase']} must be a whole number" in said


@pytest.mark.parametrize("model", SAMPLED)
def test_sampled_native_fmu_declares_its_period(model, native_fmus, twin_fmus):
    """As the twin: no variable step size, DefaultExperiment stepSize T, the sample_phase parameter."""
    twin, native = Driver(twin_fmus[model]).md, Driver(native_fmus[model]).md
    assert native.coSimulation.canHandleVariableCommunicationStepSize is False
    assert twin.coSimulation.canHandleVariableCommunicationStepSize is False
    assert float(native.defaultExperiment.stepSize) == float(twin.defaultExperiment.stepSize)
    phase = {v.name: v for v in native.modelVariables}["sample_phase"]
    assert (phase.type, phase.causality, phase.start) == ("Integer", "parameter", "0")


#: Per model: a parameter set whose design the native FMU does not carry, and what its refusal names.
UNBUILT = {
    "Derivator": ({"fc_vel": 50.0}, "fc_vel = 50.0 Hz"),
    "BalanceController": ({"yaw": False}, "parameter yaw = False: this native FMU carries the balance design"),
    "Trajectory": ({"kind": "circle", "cycles": 3}, "parameter cycles = 3: this native FMU carries the circle"),
}


@pytest.mark.parametrize("model", sorted(UNBUILT))
def test_design_parameters_away_from_the_build_are_refused_by_name(model, native_fmus, twin_fmus):
    """The twin accepts them (it designs with scipy at initialisation); the native FMU refuses
    its initialisation naming the parameter and its value, and every step after it."""
    parameters, says = UNBUILT[model]
    calls = [("set", parameters), ("setup", 0.0), ("enter",), ("exit",), ("step", 0.0, 1e-3), ("get", ["error"])]
    twin, native = Driver(twin_fmus[model]).run(calls), Driver(native_fmus[model]).run(calls)
    assert [s.status for s in twin] == [0] * 6 and twin[-1].result == [""]
    assert native[3].status == 0 and says in native[3].messages[0][2]
    assert native[4].status == 2 and says in native[-1].result[0]
