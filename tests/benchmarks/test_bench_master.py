"""The pass-through floor of benchmarks/bench_master.py: its slaves copy, its system runs (no timing)."""
import math
import random
from dataclasses import replace

import numpy as np
import pytest

from benchmarks import passthrough
from fmus.export.build import SLAVES
from fmus.cosim.master import simulate
from fmus.cosim.system import split_signal
from scenarios.scenes.catalogue import get_scene

SCENE = "bench_circle_TCMDx"
STEPS = 5


@pytest.fixture(scope="module")
def classes(tmp_path_factory):
    return passthrough.load_classes(list(SLAVES), tmp_path_factory.mktemp("pass_src"))


def _system():
    system = get_scene(SCENE).system
    return passthrough.passthrough_system(replace(system, stop_time=STEPS * system.step))


@pytest.mark.parametrize("model", list(SLAVES))
def test_passthrough_slave_has_the_real_variables_and_copies(model, classes):
    """Catches a passthrough slave (the master benchmark's stand-in) whose variables differ from the real
    slave's, or whose outputs are not the copies of their inputs (the benchmark would time another data
    flow)."""
    cls = classes[passthrough.passthrough_model(model)]
    real = passthrough.variable_specs(model)
    slave = cls(instance_name="p")
    slave.setup_experiment(0.25, None, None)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    fake = [{"name": v.name, "causality": v.causality.name if v.causality else None,
             "variability": v.variability.name if v.variability else None, "kind": type(v).__name__}
            for v in slave.vars.values() if v.name not in ("error", "refusal")]
    assert fake == [{k: s[k] for k in ("name", "causality", "variability", "kind")} for s in real]

    rng = random.Random(model)
    inputs = [s["name"] for s in real if s["causality"] == "input"]
    for name in inputs:
        setattr(slave, name, rng.uniform(-1.0, 1.0))
    assert slave.do_step(0.25, 1e-3) is True
    pairs = passthrough.copies(real)
    assert {o for o, _ in pairs} == {s["name"] for s in real if s["causality"] == "output" and s["kind"] == "Real"}
    for output, source in pairs:
        expected = getattr(slave, source) if source else 0.25 + 1e-3
        assert getattr(slave, output) == expected, output


def test_passthrough_system_runs_in_both_modes_with_outputs_equal_to_inputs(classes, tmp_path):
    """Catches the passthrough system stepped in another order than the scene, giving other rows through
    the FMUs than in process, or a connection that reads its source a step late or early."""
    system = _system()
    # Record every connected output, so each copy can be checked against its source.
    record = tuple(dict.fromkeys(list(system.record) + [c.source for c in system.connections]))
    system = replace(system, record=record)
    with passthrough.registered(classes):
        inproc = simulate(system, mode="inprocess")
    assert "PassFiveBarPlant" not in SLAVES      # the registration is undone
    passthrough.build_fmus(sorted({c.model[len(passthrough.PREFIX):] for c in system.components}), tmp_path)
    fmu = simulate(system, mode="fmu", fmu_dir=tmp_path)
    assert inproc.error is None and fmu.error is None
    assert inproc.order == fmu.order == simulate(replace(get_scene(SCENE).system, stop_time=0.0)).order
    for signal in record:
        assert len(fmu[signal]) == STEPS + 1
        assert np.array_equal(inproc[signal], fmu[signal]), signal

    # Row k + 1 holds the outputs after step k; an input read a source already stepped in
    # this step (row k + 1) or not yet (row k).
    position = {name: i for i, name in enumerate(fmu.order)}
    feeds = {c.target: c.source for c in system.connections}
    h = system.step
    for component in system.components:
        model = component.model[len(passthrough.PREFIX):]
        for output, source in passthrough.copies(passthrough.variable_specs(model)):
            signal = f"{component.name}.{output}"
            if signal not in record:
                continue
            for k in range(STEPS):
                value = fmu[signal][k + 1]
                if source is None:
                    assert math.isclose(value, (k + 1) * h, rel_tol=1e-12), signal
                    continue
                driver = feeds.get(f"{component.name}.{source}")
                if driver is None:      # unconnected input: its start value
                    assert value == 0.0, signal
                    continue
                row = k + 1 if position[split_signal(driver)[0]] < position[component.name] else k
                assert value == fmu[driver][row], (signal, driver, k)
    assert np.any(fmu["traj.x_d"] != 0.0)
