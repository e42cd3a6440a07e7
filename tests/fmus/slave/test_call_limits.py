"""Every FMI call is bounded (issue #30, item 2): the work limit of fmus/slave/budget.py and the start
times fmi2SetupExperiment refuses.

Counts, never timings: the general algorithm's right-hand sides are counted by wrapping its
forward dynamics, and a small budget (``CALL_CPU_SECONDS`` patched) makes a refusal cheap to
reach.  A step over the limit is refused before any work where the count is known (RK4, a
system FMU's inner steps), or stopped at the limit with the state unchanged (dopri5); steps
within it are the unbounded integrator's, bit for bit.
"""
from __future__ import annotations

import json
import math
import re
import shutil
from dataclasses import replace

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmus.slave import budget
from fmus.systemfmu.cores import SYSTEM_FILE, system_to_dict
from fmus.slave.base import FmiError, check_experiment_times
from plant import IntegratorSettings, PlantSimulator, get_preset
from plant.wheeled import MAX_SUBSTEPS as WHEELED_MAX_SUBSTEPS
from scenarios.scenes.catalogue import get_scene
from tests.support.fmi_support import FmuInstance
from tests.fmus.slave.test_extremes import make_slave, set_variables
from tests.support.paths import ROOT

SPECS = ROOT / "plant" / "specs"
GRAVITY = {"gravity_y": -9.81}
#: The general kernel's plants: (model, parameters) with the spec's name for SpecPlant.
GENERAL = [("FiveBarPlant", {"kernel": "general", **GRAVITY}),
           ("ActuatedFiveBarPlant", {"kernel": "general", "mode": "voltage", **GRAVITY}),
           ("SpecPlant:delta3", {}), ("SpecPlant:bench_5r", {})]


@pytest.fixture
def rhs_calls(monkeypatch):
    """Counts the general algorithm's right-hand sides (FiveBarPlant kernel 'general', SpecPlant)."""
    import plant.simulator
    import plant.specsim

    calls = [0]
    original = plant.simulator.forward_dynamics

    def counted(*args):
        calls[0] += 1
        return original(*args)

    monkeypatch.setattr(plant.simulator, "forward_dynamics", counted)
    monkeypatch.setattr(plant.specsim, "forward_dynamics", counted)
    return calls


def plant_slave(model: str, parameters: dict, tmp_path=None):
    """An initialised plant slave; ``SpecPlant:<spec>`` is a SpecPlant of the shipped spec."""
    if not model.startswith("SpecPlant:"):
        return make_slave(model, parameters)
    from fmus.slaves.parcosim_specplant import SPEC_RESOURCE, SpecPlant

    name = model.split(":")[1]
    resources = tmp_path / name
    resources.mkdir(exist_ok=True)
    shutil.copy(SPECS / f"{name}.toml", resources / SPEC_RESOURCE)
    slave = SpecPlant(instance_name=name, resources=str(resources))
    set_variables(slave, parameters)
    return slave


def sim_of(slave):
    """The plant simulator inside a plant slave."""
    return slave.actuated.plant if hasattr(slave, "actuated") else slave.sim


def system_slave(tmp_path, role: str, system, name: str = "", **parameters):
    """An initialised ClosedLoop ("loop") or ControlChain ("chain") of ``system`` in process
    (resources in ``tmp_path/<name or role>``), with the inner parameters ``parameters``
    ("plant.kernel" ...)."""
    from fmus.slaves.parcosim_closedloop import ClosedLoop
    from fmus.slaves.parcosim_controlchain import ControlChain

    if role == "loop":
        record = tuple(dict.fromkeys(("plant.x", "plant.y") + tuple(system.record)))
        system = replace(system, record=record)
    resources = tmp_path / (name or role)
    resources.mkdir()
    (resources / SYSTEM_FILE).write_text(json.dumps({"role": role, "plant": "plant",
                                                     "system": system_to_dict(system)}))
    cls = ClosedLoop if role == "loop" else ControlChain
    slave = cls(instance_name=role, resources=str(resources))
    set_variables(slave, parameters)
    assert slave._ready, slave.error
    return slave


# --- the plants' integrators ---------------------------------------------------------------------

@pytest.mark.parametrize("model, parameters", GENERAL)
def test_rk4_substeps_over_the_limit_are_refused_at_initialisation_without_evaluating(
        model, parameters, rhs_calls, tmp_path):
    """Catches a substep count whose step would exceed the per-call budget accepted (the importer then
    hangs), refused after evaluating, or refused off by one."""
    probe = plant_slave(model, parameters, tmp_path)
    unit = budget.plant_evaluation_cost("general", "rk4", budget.joints_of(sim_of(probe).mechanism))
    limit = budget.per_call(unit)
    most = limit // 4
    calls = rhs_calls[0]
    refused = plant_slave(model, {**parameters, "substeps": most + 1}, tmp_path)
    assert not refused._ready and rhs_calls[0] == calls        # refused before a single evaluation
    assert f"substeps = {most + 1}" in refused.error
    assert f"needs {4 * (most + 1)} right-hand-side evaluations" in refused.error
    assert f"more than the {limit} allowed per call" in refused.error and f"use substeps <= {most}" in refused.error
    assert plant_slave(model, {**parameters, "substeps": most}, tmp_path)._ready


def test_the_compiled_integrators_fit_one_call_at_any_substeps():
    """No refusal needed: the most substeps allowed take well under a call."""
    from plant.simulator import MAX_SUBSTEPS

    assert 4 * MAX_SUBSTEPS * budget.FAST_RK4_EVALUATION <= budget.CALL_CPU_SECONDS
    assert 4 * WHEELED_MAX_SUBSTEPS * budget.WHEELED_RK4_EVALUATION <= budget.CALL_CPU_SECONDS
    slave = make_slave("FiveBarPlant", {"substeps": MAX_SUBSTEPS})
    assert slave._ready and slave.do_step(0.0, 1e-3), slave.error


@pytest.mark.parametrize("model, parameters", GENERAL + [("FiveBarPlant", {"kernel": "fast", **GRAVITY})])
def test_a_dopri5_step_that_exhausts_the_limit_is_refused_and_changes_nothing(
        model, parameters, rhs_calls, monkeypatch, tmp_path):
    """Catches an adaptive step that overruns the call budget, or that is refused with a half-advanced
    state or outputs, so that restoring the state does not give the same run."""
    slave = plant_slave(model, {**parameters, "method": "dopri5"}, tmp_path)
    sim = sim_of(slave)
    assert slave.do_step(0.0, 1e-3), slave.error
    before = slave._get_fmu_state()
    y, outputs = sim.y.copy(), {v.name: getattr(slave, v.name) for v in slave.vars.values()}
    unit = budget.plant_evaluation_cost(sim.settings.kernel, "dopri5", budget.joints_of(sim.mechanism))
    monkeypatch.setattr(budget, "CALL_CPU_SECONDS", 40 * unit)     # 40 evaluations
    calls = rhs_calls[0]
    assert not slave.do_step(1e-3, 1.0)
    used = int(slave.error.split("dopri5 stopped after ")[1].split(",")[0])
    assert 40 - 6 < used <= 40
    if sim.settings.kernel == "general":
        assert rhs_calls[0] - calls == used
    assert "step size h = 1.0 s at t = 0.001 s needs more right-hand-side evaluations" in slave.error
    assert "than the 40 one call may take" in slave.error and "nothing changed" in slave.error
    assert np.array_equal(sim.y, y) and sim.time == 1e-3
    assert {v.name: getattr(slave, v.name) for v in slave.vars.values() if v.name not in ("error", "refusal")} == \
        {name: value for name, value in outputs.items() if name not in ("error", "refusal")}
    monkeypatch.undo()
    slave._set_fmu_state(before)          # as before the refused step: it goes on
    assert slave.do_step(1e-3, 1e-3), slave.error
    twin = plant_slave(model, {**parameters, "method": "dopri5"}, tmp_path)
    assert twin.do_step(0.0, 1e-3) and twin.do_step(1e-3, 1e-3)
    assert np.array_equal(sim_of(slave).y, sim_of(twin).y)


def test_actuated_plant_refused_by_the_limit_keeps_its_current_controllers(monkeypatch):
    """In current mode the controllers sample before the integration: a stopped step puts them back."""
    slave = make_slave("ActuatedFiveBarPlant", {"kernel": "general", "method": "dopri5", **GRAVITY})
    assert slave.do_step(0.0, 1e-3), slave.error
    drives = [d for _, d in slave.actuated.drives]
    before = [d.controller_state() for d in drives]
    monkeypatch.setattr(budget, "CALL_CPU_SECONDS", 1e-3)       # not one dopri5 attempt
    assert not slave.do_step(1e-3, 1e-3)
    assert "dopri5 stopped after 0" in slave.error
    for d, (buf, controller) in zip(drives, before):
        now_buf, now_controller = d.controller_state()
        assert np.array_equal(now_buf, buf) and np.array_equal(now_controller, controller)


@pytest.mark.parametrize("kernel", ["fast", "general"])
def test_steps_within_the_limit_are_the_unbounded_integrators(kernel):
    """Normal 1 ms steps, dopri5 at its default tolerances: the same bits as without a limit."""
    slave = make_slave("FiveBarPlant", {"kernel": kernel, "method": "dopri5", **GRAVITY})
    params = replace(get_preset("bench"), gravity=(0.0, -9.81, 0.0))
    free = PlantSimulator(params, slave.x0, slave.y0, IntegratorSettings(method="dopri5", kernel=kernel))
    slave.tau1, slave.tau2 = 0.01, -0.01
    for k in range(20):
        assert slave.do_step(k * 1e-3, 1e-3), slave.error
        free.step(0.01, -0.01, 1e-3)
    assert np.array_equal(slave.sim.y, free.y)


# --- system FMUs ---------------------------------------------------------------------------------

@pytest.mark.parametrize("scene", ["bench_circle_TCMDx", "pendulum_balance"])
def test_closed_loop_refuses_a_huge_step_before_any_inner_step(scene, tmp_path):
    """The hang of the campaign: doStep(0, 1e9) ran 1e12 inner steps."""
    slave = system_slave(tmp_path, "loop", get_scene(scene).system)
    stepper = slave.core.stepper
    values = list(stepper.values)
    count, seconds = slave.core.work_per_step()
    limit = budget.per_call(seconds / count)
    assert not slave.do_step(0.0, 1e9)
    assert stepper.time == 0.0 and stepper.values == values        # no inner step was taken
    assert f"step size h = 1000000000.0 s at t = 0.0 s needs {1e12 * count:.6g} inner steps of ClosedLoop's system" \
        in slave.error
    assert f"more than the {limit} one call may take" in slave.error


def test_closed_loop_counts_its_plants_rk4_evaluations_before_stepping(rhs_calls, monkeypatch, tmp_path):
    """A general-kernel plant inside: 4 evaluations an inner step; 50 ms of budget fit 6 steps."""
    monkeypatch.setattr(budget, "CALL_CPU_SECONDS", 0.05)
    system = get_scene("thesis_sim_circle").system
    slave = system_slave(tmp_path, "loop", system, **{"plant.kernel": "general"})
    count, seconds = slave.core.work_per_step()
    fit = math.floor(0.05 / seconds)
    assert fit == 6     # 3 components, the plant's 4 evaluations at ~2 ms
    calls = rhs_calls[0]
    assert not slave.do_step(0.0, (fit + 1) * 1e-3)
    assert rhs_calls[0] == calls and slave.core.stepper.time == 0.0
    assert f"needs {(fit + 1) * count} inner steps" in slave.error
    assert f"take steps of at most {fit * 1e-3:.6g} s" in slave.error
    fresh = system_slave(tmp_path, "loop", system, "fresh", **{"plant.kernel": "general"})
    assert fresh.do_step(0.0, fit * 1e-3), fresh.error
    assert rhs_calls[0] - calls == 4 * fit


def test_closed_loop_with_dopri5_stops_mid_step_and_restores(monkeypatch, tmp_path):
    """dopri5's evaluations are not known before: the inner plant stops at what is left of the
    call, the loop's step is refused naming it, and a state taken before goes on as if nothing happened."""
    system = get_scene("thesis_sim_circle").system
    tight = {"plant.kernel": "general", "plant.method": "dopri5", "plant.rtol": 1e-14, "plant.atol": 1e-17}
    slave = system_slave(tmp_path, "loop", system, **tight)
    twin = system_slave(tmp_path, "loop", system, "twin", **tight)
    assert slave.do_step(0.0, 1e-3) and twin.do_step(0.0, 1e-3)
    before = slave._get_fmu_state()
    unit = budget.plant_evaluation_cost("general", "dopri5", 4)
    monkeypatch.setattr(budget, "CALL_CPU_SECONDS", 60 * unit)
    assert not slave.do_step(1e-3, 5e-3)          # passes the count (7 evaluations a step at least), then stops
    assert "plant" in slave.error and "dopri5 stopped after" in slave.error
    assert "left of this call's" in slave.error
    monkeypatch.undo()
    slave._set_fmu_state(before)
    for k in range(1, 6):
        assert slave.do_step(k * 1e-3, 1e-3) and twin.do_step(k * 1e-3, 1e-3)
    assert (slave.x, slave.y) == (twin.x, twin.y)


def test_control_chain_counts_the_model_of_the_plant_and_its_correction(rhs_calls, monkeypatch, tmp_path):
    """One step of the chain steps its model of the plant twice at most (the correction redoes it)."""
    from scenarios.packaging.chain import package_scene

    monkeypatch.setattr(budget, "CALL_CPU_SECONDS", 0.05)
    chain = package_scene(get_scene("bench_circle_TCMDx")).chain
    slave = system_slave(tmp_path, "chain", chain, **{"plant.kernel": "general", "plant.substeps": 4})
    count, seconds = slave.core.work_per_step()
    assert count == len(chain.components) + 1 and seconds > 0.05     # 2 x 16 evaluations at ~2 ms
    calls = rhs_calls[0]
    assert not slave.do_step(0.0, 1e-3)
    assert rhs_calls[0] == calls and f"needs {count} inner steps of ControlChain's system" in slave.error


def test_control_chain_names_the_step_it_accepts_not_the_limit(tmp_path):
    """Catches the ControlChain answering a huge step with a budget message instead of the step size it
    accepts."""
    slave = system_slave(tmp_path, "chain", get_scene("bench_circle_TCMDx").system)
    assert not slave.do_step(0.0, 1e9)
    assert "the step size must be h = 0.001 s" in slave.error


# --- start times ---------------------------------------------------------------------------------

@pytest.mark.parametrize("start, stop, named", [
    (-math.inf, None, "startTime = -inf"), (math.nan, None, "startTime = nan"), (-1e20, None, "startTime = -1e+20"),
    (1e17, None, "startTime = 1e+17"), (0.0, math.inf, "stopTime = inf"), (1.0, 0.5, "stopTime = 0.5 s is before"),
])
def test_start_times_time_cannot_advance_from_are_refused(start, stop, named):
    """Catches start times where t + 1 µs == t (time would stand still) or a stop time before the start
    accepted."""
    with pytest.raises(FmiError, match=re.escape(named)):
        check_experiment_times(start, stop)


@pytest.mark.parametrize("start", [0.0, -1e9, 1e9, 5e9])
def test_start_times_a_microsecond_can_follow_are_accepted(start):
    """Catches the start-time check refusing ordinary large or negative start times."""
    check_experiment_times(start, start + 1.0)
    assert start + 1e-6 != start


@pytest.mark.parametrize("model", ["Trajectory", "FiveBarPlant"])
def test_a_refused_start_time_is_an_fmi_error_and_the_instance_stays_usable(model, built_fmus):
    """Catches a refused fmi2SetupExperiment that returns fmi2Fatal, or that changes the start time it
    refused, so the instance cannot go on."""
    fmu = FmuInstance(built_fmus[model], instance_name="t", setup=False)
    raw = fmu.fmu
    raw.setupExperiment(startTime=2.0)
    for start in (-math.inf, -1e20, math.nan):
        with pytest.raises(FMICallException) as info:
            raw.setupExperiment(startTime=start)
        assert info.value.status == 3                       # fmi2Error, never fmi2Fatal
        assert f"startTime = {start!r}" in fmu.messages[-1]
    with pytest.raises(FMICallException) as info:
        raw.setupExperiment(startTime=2.0, stopTime=1.0)
    assert info.value.status == 3 and "stopTime = 1.0 s is before startTime = 2.0 s" in fmu.messages[-1]
    assert raw.getRealStatus(2) == 2.0           # fmi2LastSuccessfulTime: the refusals changed nothing
    raw.enterInitializationMode()
    raw.exitInitializationMode()
    raw.doStep(currentCommunicationPoint=2.0, communicationStepSize=1e-3)     # the start time set before
    assert fmu.get("error") == ""
    fmu.close()
