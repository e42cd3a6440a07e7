"""FMU state (issue 12.5): get/set and serialise/deserialise continue a run bit for bit.

For every parcosim model, in process and as a built FMU through fmpy, and for the FMUs
that contain a whole system (ClosedLoop, ControlChain): a snapshot taken mid-run, restored
(twice) or serialised into a fresh instance, continues exactly as the run did.  The runs
keep the filters, the adaptive gain, the tables' caches, the drives' controllers and the
plant's integrator moving, so a state that missed any of them would continue differently.
"""
from __future__ import annotations

import numpy as np
import pytest

from fmus.cosim.backends import InProcessInstance, _FmuInstance
from fmus.cosim.master import simulate, stepping_order
from fmus.cosim.stepper import Stepper
from fmus.cosim.system import Component, System
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant

BEFORE, AFTER = 150, 60


def _scenes():
    return {"bench": get_scene("bench_circle_TCMDx").system,
            "thesis_sim": get_scene("thesis_sim_circle").system,
            "actuated": drives_in_plant(get_scene("bench_circle_PDMDx"), substeps=2).system}


def _stepper(system, make):
    instances = {c.name: make(c) for c in system.components}
    return Stepper(system, instances, stepping_order(system, {n: i.variables for n, i in instances.items()}))


def _run(stepper, steps):
    rows = []
    for _ in range(steps):
        stepper.step()
        rows.append(stepper.row())
    return np.array(rows)


def _close(stepper):
    for inst in stepper.instances.values():
        inst.close()


def _check_continuations(system, make):
    """Mid-run snapshot; the continuation, after restoring twice and in fresh instances
    given the serialised states, equals the run's own, to the bit."""
    stepper = _stepper(system, make)
    stepper.initialize(0.0)
    _run(stepper, BEFORE)
    time = stepper.time
    snapshot = stepper.state()
    serialised = {n: inst.serialize_state(snapshot["instances"][n]) for n, inst in stepper.instances.items()}
    reference = _run(stepper, AFTER)
    assert not np.array_equal(reference[0], reference[-1]), "the run must move after the snapshot"
    for _ in range(2):
        stepper.restore(snapshot)
        assert stepper.time == time
        np.testing.assert_array_equal(_run(stepper, AFTER), reference)
    for name, inst in stepper.instances.items():
        inst.free_state(snapshot["instances"][name])
    _close(stepper)

    fresh = _stepper(system, make)   # instantiated only: no parameters, no initialisation
    try:
        for name, inst in fresh.instances.items():
            state = inst.deserialize_state(serialised[name])
            inst.set_state(state)
            inst.free_state(state)
        fresh.values[:] = snapshot["values"]
        fresh.at_step(snapshot["step"], snapshot["start_time"])
        np.testing.assert_array_equal(_run(fresh, AFTER), reference)
    finally:
        _close(fresh)


@pytest.mark.parametrize("scene", ["bench", "thesis_sim", "actuated"])
def test_in_process_state_continues_bit_for_bit(scene):
    """Catches a slave state (get/set) that misses part of a model's state in process: the run continued
    from it differs from the uninterrupted one."""
    _check_continuations(_scenes()[scene], lambda c: InProcessInstance(c.model, c.name))


@pytest.mark.parametrize("scene", ["bench", "thesis_sim", "actuated"])
def test_fmu_state_continues_bit_for_bit(scene, built_fmus):
    """Catches an FMU state (fmi2Get/SetFMUstate through the built FMUs) that misses part of a model's
    state: the continued run differs bit for bit."""
    _check_continuations(_scenes()[scene], lambda c: _FmuInstance(built_fmus[c.model], c.name))


@pytest.fixture(scope="module")
def system_fmus(tmp_path_factory):
    """The ClosedLoop of the bench scene and the ControlChain of its package."""
    from fmus.systemfmu.export import build_system_fmu, export_fmu
    from scenarios.packaging.chain import PLANT, package_scene

    out = tmp_path_factory.mktemp("system_fmus")
    package = package_scene(get_scene("bench_circle_TCMDx"))
    return {"ClosedLoop": export_fmu(get_scene("bench_circle_TCMDx").system, out / "loop.fmu"),
            "ControlChain": build_system_fmu("chain", package.chain, out / "chain.fmu", PLANT)}


def _bind_all(inst):
    """Bind every Real input and output; return the inputs' names."""
    inputs = [v for v in inst.variables.values() if v.causality == "input" and v.type == "Real"]
    outputs = [v for v in inst.variables.values() if v.causality == "output" and v.type == "Real"]
    inst.bind(inputs, outputs)
    return [v.name for v in inputs]


def _measurements(names):
    """The bench plant's outputs ``names`` at its start (what the chain measures)."""
    plant = InProcessInstance("FiveBarPlant", "plant")
    plant.initialize(get_scene("bench_circle_TCMDx").system.component("plant").parameters, 0.0)
    return [getattr(plant.slave, name) for name in names]


def _steps(inst, start, k0, steps, h=1e-3):
    """``steps`` steps from step k0; inputs (the chain's measurements) drift slowly away
    from ``start``, so the chain's model keeps correcting itself."""
    rows = []
    for k in range(k0, k0 + steps):
        if start:
            inst.set_inputs([value + 2e-6 * k for value in start])
        inst.do_step(k * h, h)
        rows.append(inst.get_outputs())
    return np.array(rows)


@pytest.mark.parametrize("model", ["ClosedLoop", "ControlChain"])
def test_system_fmu_state_is_the_whole_inner_system(model, system_fmus):
    """Catches a system FMU's state that leaves out an inner component or its time, so restoring it (or
    deserialising it into a fresh instance) continues differently."""
    path = system_fmus[model]
    inst = _FmuInstance(path, "a")
    start = _measurements(_bind_all(inst))
    inst.initialize({}, 0.0)
    _steps(inst, start, 0, BEFORE)
    state = inst.get_state()
    data = inst.serialize_state(state)
    reference = _steps(inst, start, BEFORE, AFTER)
    assert not np.array_equal(reference[0], reference[-1])
    inst.set_state(state)
    np.testing.assert_array_equal(_steps(inst, start, BEFORE, AFTER), reference)
    inst.free_state(state)
    inst.close()

    fresh = _FmuInstance(path, "b")   # instantiated only
    _bind_all(fresh)
    restored = fresh.deserialize_state(data)
    fresh.set_state(restored)
    fresh.free_state(restored)
    np.testing.assert_array_equal(_steps(fresh, start, BEFORE, AFTER), reference)
    fresh.close()


def test_after_set_state_the_system_fmu_time_is_the_states(system_fmus):
    """Catches a system FMU that keeps its later time after fmi2SetFMUstate (a step from the state's time
    refused, a later one accepted)."""
    from fmus.cosim.master import CoSimulationError

    inst = _FmuInstance(system_fmus["ClosedLoop"], "loop")
    _bind_all(inst)
    inst.initialize({}, 0.0)
    _steps(inst, [], 0, 10)
    state = inst.get_state()
    _steps(inst, [], 10, 5)
    inst.set_state(state)
    with pytest.raises(CoSimulationError, match=r"t = 0.015 s does not follow the last one: the next doStep must start at t = 0.01"):
        inst.do_step(0.015, 1e-3)
    inst.set_state(state)   # a state taken before the refusal clears it
    _steps(inst, [], 10, 1)
    inst.free_state(state)
    inst.close()


@pytest.mark.parametrize("backend", ["inprocess", "fmu"])
def test_restoring_a_state_taken_before_a_refused_step_clears_the_refusal(backend, built_fmus):
    """The plant refuses a NaN torque and every step after; set back to the state before,
    it steps again exactly as from that state."""
    from fmus.cosim.master import CoSimulationError

    make = {"inprocess": lambda: InProcessInstance("FiveBarPlant", "plant"),
            "fmu": lambda: _FmuInstance(built_fmus["FiveBarPlant"], "plant")}[backend]
    inst = make()
    variables = inst.variables
    inst.bind([variables["tau1"], variables["tau2"]], [variables["x"], variables["y"]])
    inst.initialize({}, 0.0)
    inst.set_inputs([0.01, -0.02])
    inst.do_step(0.0, 1e-3)
    state = inst.get_state()
    inst.do_step(1e-3, 1e-3)
    reference = inst.get_outputs()
    inst.set_inputs([float("nan"), 0.0])
    with pytest.raises(CoSimulationError, match="tau1"):
        inst.do_step(2e-3, 1e-3)
    inst.set_inputs([0.01, -0.02])
    with pytest.raises(CoSimulationError):
        inst.do_step(2e-3, 1e-3)   # refused for good ...
    inst.set_state(state)          # ... until a state from before the refusal is set
    inst.do_step(1e-3, 1e-3)
    assert inst.get_outputs() == reference
    inst.free_state(state)
    inst.close()


@pytest.mark.parametrize("model", ["FiveBarPlant", "DCMotorDrive", "CurrentObserver", "Derivator",
                                   "PositionController", "Trajectory", "ActuatedFiveBarPlant"])
def test_every_fmu_declares_state_capabilities(model, built_fmus):
    """Catches an FMU that can get, set and serialise its state but does not declare it."""
    from fmpy import read_model_description

    cs = read_model_description(str(built_fmus[model])).coSimulation
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate


# --- the master retries a refused step from the state before it (issue 12.6) ---------------

def _spin_up(stop_time=0.3):
    """thesis_sim arms from rest under a constant 3 N m / -3 N m torque step, no controller,
    the state projected on the constraints after every step: they spin up to ~150 rad/s,
    and at t = 0.165 s a full 1 ms RK4 step ends in a pose the plant refuses as singular."""
    plant = Component("plant", "FiveBarPlant", {"preset": "thesis_sim", "tau1": 3.0, "tau2": -3.0, "project": True})
    return System((plant,), (), ("plant.x", "plant.y", "plant.residual"), stop_time)


@pytest.mark.parametrize("mode", ["inprocess", "fmu"])
def test_retry_in_sub_steps_completes_a_run_a_full_step_stops(mode, built_fmus):
    """Catches --retry-substeps not retrying the refused step from the state before it (the run still
    stops), retrying elsewhere, or changing the rows before the refusal."""
    fmu_dir = next(iter(built_fmus.values())).parent
    stopped = simulate(_spin_up(), mode=mode, fmu_dir=fmu_dir)
    assert not stopped.completed and "plant refused the step from t = 0.165 s" in str(stopped.error)
    retried = simulate(_spin_up(), mode=mode, fmu_dir=fmu_dir, retry_substeps=4)
    assert retried.completed
    assert [(round(t, 9), name) for t, name in retried.extra["retried"]] == [(0.165, "plant")]
    # Until the refusal the option changes nothing; afterwards the loop still closes.
    rows = len(stopped.time)
    np.testing.assert_array_equal(retried["plant.x"][:rows], stopped["plant.x"])
    assert retried["plant.residual"].max() < 1e-9


def test_without_retry_no_state_is_taken(monkeypatch):
    """Catches a master that takes FMU states on every step when no retry is asked for."""
    monkeypatch.setattr(InProcessInstance, "get_state", lambda self: pytest.fail("state taken"))
    assert simulate(_spin_up(0.01)).completed


def test_retry_substeps_must_split_the_step():
    """Catches retry_substeps = 1 accepted (a retry that does not split the step)."""
    with pytest.raises(ValueError, match="retry_substeps = 1 must be an integer >= 2"):
        simulate(_spin_up(0.01), retry_substeps=1)
