"""The master's run structure (fmus/cosim/master.py, context.py, stepper.py): a compiled run whose
adapter declines a component's settings goes on in process from the instances it already loaded
and initialised (it loaded and initialised everything twice before); the step's program is one
flat sequence of records; the rows are those of the in-process run."""
from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim import backends
from fmus.cosim.master import simulate
from fmus.cosim.stepper import Call, Entry, Group
from scenarios.scenes.catalogue import get_scene


def _system(stop_time=0.05, **plant):
    system = get_scene("bench_circle_PDq").system
    components = tuple(replace(c, parameters={**c.parameters, **plant}) if c.name == "plant" else c
                       for c in system.components)
    return replace(system, components=components, stop_time=stop_time)


def _counting(monkeypatch):
    """Count InProcessInstance constructions and initialisations (exit_initialization calls)."""
    counts = {"instances": 0, "initialised": 0}
    init, exit_init = backends.InProcessInstance.__init__, backends.InProcessInstance.exit_initialization

    def counted_init(self, *args, **kwargs):
        counts["instances"] += 1
        init(self, *args, **kwargs)

    def counted_exit(self):
        counts["initialised"] += 1
        exit_init(self)

    monkeypatch.setattr(backends.InProcessInstance, "__init__", counted_init)
    monkeypatch.setattr(backends.InProcessInstance, "exit_initialization", counted_exit)
    return counts


def test_a_declined_setting_falls_back_without_loading_or_initialising_twice(monkeypatch):
    """Catches the compiled mode's fallback loading or initialising the components a second time, or its
    in-process run giving other rows than a plain in-process run."""
    system = _system(method="dopri5")      # the plant's adaptive integrator has no compiled step
    counts = _counting(monkeypatch)
    with pytest.warns(UserWarning, match="compiled mode: component plant: .*method='dopri5'.*running in process"):
        fast = simulate(system, mode="compiled")
    n = len(system.components)
    assert counts == {"instances": n, "initialised": n}
    assert fast.mode == "inprocess" and "method='dopri5'" in fast.extra["fallback"] and fast.error is None
    slow = simulate(system, mode="inprocess")
    assert np.array_equal(np.column_stack([fast[s] for s in system.record]),
                          np.column_stack([slow[s] for s in system.record]))


def test_a_compiled_run_loads_and_initialises_once(monkeypatch):
    """Catches the compiled mode instantiating or initialising a component twice (once to judge
    compilability, once to run)."""
    system = _system()
    counts = _counting(monkeypatch)
    result = simulate(system, mode="compiled")
    assert result.mode == "compiled" and "fallback" not in result.extra
    assert counts == {"instances": len(system.components), "initialised": len(system.components)}


def test_the_plan_and_program_are_records_in_stepping_order():
    """Catches a plan or program whose records are out of stepping order, a multi-rate group unrolled with
    wrong offsets or step sizes, or outputs not laid out as one slice per instance."""
    from fmus.cosim.master import _close, _instantiate, stepping_order
    from fmus.cosim.stepper import Stepper

    system = replace(_system(), components=tuple(replace(c, substeps=2) if c.name in ("drive1", "drive2", "plant")
                                                 else c for c in _system().components))
    instances = _instantiate(system, "inprocess", None)
    try:
        stepper = Stepper(system, instances, stepping_order(system, {n: i.variables for n, i in instances.items()}))
        assert all(isinstance(e, Entry) for e in stepper.plan) and all(isinstance(g, Group) for g in stepper.groups)
        assert [e.name for e in stepper.plan] == list(stepper.order)
        assert [e.name for g in stepper.groups for e in g.entries] == list(stepper.order)
        # drives and plant: one group of 2 sub-steps, unrolled: each of the three twice, offsets 0 and h/2
        calls = stepper._program.calls
        assert all(isinstance(c, Call) for c in calls)
        assert len(calls) == len(system.components) + 3
        h = system.step
        tail = [(c.instance.name, c.offset, c.dt) for c in calls[-6:]]
        assert tail == [(n, j * h / 2, h / 2) for j in (0, 1) for n in ("drive1", "drive2", "plant")]
        for entry in stepper.plan:   # each instance's outputs are one slice of the values
            assert list(entry.out_slots) == list(range(entry.out_slots[0], entry.out_slots[0] + len(entry.out_slots)))
    finally:
        _close(instances)
