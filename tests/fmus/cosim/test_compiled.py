"""The compiled mode (fmus.cosim.compiled): the same rows as in process, refusals, fall-backs.

The loop is C (kernels/src/loop.c) over a plan of data: nothing is compiled per wiring.
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim import compiled
from fmus.cosim.master import simulate
from fmus.cosim.system import Component, System
from scenarios.run.runner import run_scene
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant
from tests.support.inprocess import python_slaves


def _short(scene, stop_time):
    return replace(scene, system=replace(scene.system, stop_time=stop_time))


def _with(scene, instance, **parameters):
    components = tuple(replace(c, parameters={**c.parameters, **parameters}) if c.name == instance else c
                       for c in scene.system.components)
    return replace(scene, system=replace(scene.system, components=components))


def _same_rows(a, b):
    assert a.signals.keys() == b.signals.keys()
    for name in a.signals:
        assert np.array_equal(a[name], b[name], equal_nan=True), name


@pytest.mark.parametrize("name, drives_inside", [("bench_circle_TCMDx", False), ("bench_circle_TCMDx", True),
                                                 ("thesis_sim_circle_me20", False)],
                         ids=["bench", "drives_in_plant", "thesis_exact_model"])
def test_compiled_rows_are_the_in_process_rows(name, drives_inside):
    """Catches a compiled loop whose rows differ from the in-process run by a bit."""
    scene = _short(get_scene(name), 1.5)
    if drives_inside:
        scene = drives_in_plant(scene, substeps=2)
    fast = simulate(scene.system, mode="compiled")
    with python_slaves():   # every slave through its Python step, not the kernels
        slow = simulate(scene.system, mode="inprocess")
    assert fast.error is None and fast.mode == "compiled" and "fallback" not in fast.extra
    assert fast.extra["python_steps"] == 0
    _same_rows(fast, slow)
    assert len(fast.time) == 1501


def test_every_parameter_a_sweep_perturbs_reaches_the_compiled_loop():
    """A sweep's robot (scenarios.scenes.perturb: chain geometry and inertia, encoder zero errors,
    motor constants with the nominal current-controller design) runs the same rows compiled
    as in process: an adapter that left a parameter to the Python path would differ here."""
    from scenarios.scenes.perturb import draw, perturbable, perturbed, uncertainties

    base = _short(get_scene("bench_circle_TCMDq"), 1.0)
    parameters = perturbable(base)
    values = draw(parameters, uncertainties(parameters, 0.4), 0, 1)
    assert any(name.endswith("encoder_offset1") for name in values)
    scene = perturbed(base, parameters, values)
    fast = simulate(scene.system, mode="compiled")
    with python_slaves():   # every slave through its Python step, not the kernels
        slow = simulate(scene.system, mode="inprocess")
    assert fast.error is None and fast.extra["python_steps"] == 0
    _same_rows(fast, slow)


def test_a_sample_off_the_table_is_taken_by_python_and_the_loop_goes_on():
    # The controller's table covers only x <= 0.02 m: on the rest of the circle the compiled
    # law declines and the Python controller evaluates the exact model there (table_fallback).
    """Catches a compiled loop that stops or differs where the table declines a sample."""
    scene = _with(_short(get_scene("bench_circle_TCx"), 1.2), "ctrl", x_max=0.02)
    fast = simulate(scene.system, mode="compiled")
    with python_slaves():   # every slave through its Python step, not the kernels
        slow = simulate(scene.system, mode="inprocess")
    assert fast.error is None
    assert 100 < fast.extra["python_steps"] < 1200
    _same_rows(fast, slow)


def test_a_refusal_stops_at_the_same_step_with_the_same_message():
    """Catches a compiled refusal at another step or with another message than in process."""
    scene = _with(_short(get_scene("bench_circle_TCx"), 1.2), "ctrl", x_max=0.02, table_fallback=False)
    fast = run_scene(scene, mode="compiled")
    with python_slaves():   # every slave through its Python step, not the kernels
        slow = run_scene(scene, mode="inprocess")
    assert "outside the tabulated region" in str(slow.result.error) and slow.result.error.instance == "ctrl"
    assert fast.result.error == slow.result.error
    assert fast.metrics["completed"] is False
    assert 10 < len(fast.result.time) < 1201 and len(fast.result.time) == len(slow.result.time)
    _same_rows(fast.result, slow.result)


def test_a_refused_sample_runs_once_its_record_from_the_kernel(monkeypatch):
    # Off the table without table_fallback: the law's kernel refuses its sample at some step k.
    """Catches a compiled loop that runs a declined controller sample again in Python to learn
    its refusal (counted: the Python law runs no sample at all), or whose record differs."""
    from controller.position import PositionController

    runs = []
    python_sample = PositionController.step_with_errors

    def counted(self, t, *args, **kwargs):
        runs.append(t)
        return python_sample(self, t, *args, **kwargs)

    monkeypatch.setattr(PositionController, "step_with_errors", counted)
    scene = _with(_short(get_scene("bench_circle_TCx"), 1.2), "ctrl", x_max=0.02, table_fallback=False)
    fast = simulate(scene.system, mode="compiled")
    assert runs == [] and fast.mode == "compiled" and fast.extra["python_steps"] == 0
    with python_slaves():
        slow = simulate(scene.system, mode="inprocess")
    assert len(runs) == len(slow.time) and runs[-1] == slow.error.time    # Python slaves: one a step, the last refused
    assert fast.error == slow.error and fast.error.variable and fast.error.code is not None
    _same_rows(fast, slow)


@pytest.mark.parametrize("model, parameters, variable", [
    ("FiveBarPlant", {"preset": "thesis_sim", "tau1": 3.0, "tau2": -3.0}, "residual"),
    ("FiveBarPlant", {"preset": "thesis_sim", "tau1": 3.0, "tau2": -3.0, "substeps": 16}, "chain 1 elbow (serial)"),
    ("ActuatedFiveBarPlant", {"mode": "voltage", "v_ref1": 200.0, "v_ref2": -200.0, "v_max1": 200.0,
                              "v_max2": 200.0}, "residual")], ids=["diverged", "singular", "actuated"])
def test_a_refused_plant_step_runs_once_its_record_from_the_kernel(monkeypatch, model, parameters, variable):
    # The thesis_sim arms under a constant 3 N m torque step spin up until an RK4 step of 1 ms
    # no longer closes the loop (t = 0.116 s), or, in 16 RK4 steps, reach a singular pose
    # (t = 0.352 s; its message gives the refused trial pose); the bench arms driven at 200 V
    # diverge at t = 0.05 s: the plant's kernel refuses the step.
    """Catches a compiled loop that takes a plant step its kernel refused again in Python to learn
    the refusal (counted: the Python plant steps none), or whose record differs from in process."""
    from plant.actuated import ActuatedPlant
    from plant.simulator import PlantSimulator

    runs = []
    for cls in (PlantSimulator, ActuatedPlant):
        def counted(self, *args, python_step=cls.step, **kwargs):
            runs.append(cls)
            return python_step(self, *args, **kwargs)

        monkeypatch.setattr(cls, "step", counted)
    plant = Component("plant", model, parameters)
    system = System((plant,), (), ("plant.x", "plant.y", "plant.residual"), 0.5)
    fast = simulate(system, mode="compiled")
    assert runs == [] and fast.mode == "compiled" and fast.extra["python_steps"] == 0
    with python_slaves():
        slow = simulate(system, mode="inprocess")
    assert len(runs) == len(slow.time) and slow.error.variable == variable and 0.04 < slow.error.time < 0.5
    assert fast.error == slow.error
    _same_rows(fast, slow)


def test_foreign_fmus_jacobi_and_retries_fall_back_with_a_reason():
    """Catches compiled mode accepting a foreign FMU, Jacobi or retries, or falling back silently."""
    system = System((Component("drive1", "/tmp/supplier_drive.fmu"),), (), (), stop_time=0.01)
    with pytest.raises(compiled.NotCompilable, match=r"drive1 is an FMU file \(supplier_drive.fmu\)"):
        compiled.check_compilable(system, "gauss-seidel", None)
    scene = _short(get_scene("thesis_sim_circle"), 0.01)
    with pytest.raises(compiled.NotCompilable, match="Gauss-Seidel only"):
        compiled.check_compilable(scene.system, "jacobi", None)
    with pytest.raises(compiled.NotCompilable, match="retry_substeps"):
        compiled.check_compilable(scene.system, "gauss-seidel", 4)
    with pytest.warns(UserWarning, match="compiled mode: coupling 'jacobi'.*running in process instead"):
        result = simulate(scene.system, mode="compiled", coupling="jacobi")
    assert result.mode == "inprocess" and "Gauss-Seidel only" in result.extra["fallback"]


def test_metrics_report_compile_time_and_peak_memory():
    """Catches compiled-run metrics without compile time, memory or with Python steps."""
    outcome = run_scene(_short(get_scene("bench_circle_PDq"), 0.2), mode="compiled")
    m = outcome.metrics
    assert m["mode"] == "compiled" and m["compile_s"] > 0.0 and m["python_steps"] == 0
    assert m["peak_rss_mb"] > 10.0 and math.isfinite(m["realtime_factor"])


def test_generated_source_follows_the_stepping_order():
    """Catches a compiled plan that steps members out of the master's order."""
    scene = _short(get_scene("bench_circle_PDq"), 0.01)
    result = simulate(scene.system, mode="compiled")
    source = result.extra["plan"]
    positions = [source.index(f"# {name} (") for name in result.order]
    assert positions == sorted(positions)
    assert compiled.ADAPTERS.keys() >= {c.model for c in scene.system.components}


def test_python_finishes_a_declined_step_from_the_declining_member_and_sub_step():
    """Catches Python redoing or skipping members when it finishes a declined step."""
    from fmus.cosim.stepper import Entry, Stepper, rate_groups

    calls = []

    class Instance:
        def __init__(self, name):
            self.name = name

        def set_inputs(self, values):
            pass

        def do_step(self, t, h):
            calls.append((self.name, t, h))

        def get_outputs(self):
            return []

    a, b, c, d = (Instance(n) for n in "abcd")
    stepper = Stepper.__new__(Stepper)
    stepper.system = System((), (), (), stop_time=1.0, step=1.0)
    stepper.values, stepper.jacobi, stepper._calls = [], False, {}
    stepper.start_time, stepper.k, stepper.time = 0.0, 3, 3.0
    stepper.plan = tuple(Entry(i.name, i, (), (), (), (), n) for i, n in ((a, 1), (b, 2), (c, 2), (d, 1)))
    stepper.groups = tuple(rate_groups(stepper.plan))
    stepper._program = stepper._program_of(stepper.groups)
    stepper.step(start=(1, 1, 0))   # c declined in the first of b, c's two sub-steps
    assert calls == [("c", 3.0, 0.5), ("b", 3.5, 0.5), ("c", 3.5, 0.5), ("d", 3.0, 1.0)]
    assert stepper.time == 4.0
    calls.clear()
    stepper.step()
    assert [n for n, _, _ in calls] == ["a", "b", "c", "b", "c", "d"]


@pytest.mark.parametrize("name", ["pendulum_balance", "pendulum_push"])
def test_the_pendulum_scenes_compiled_are_the_in_process_rows(name):
    # One compiled loop: both scenes share the wiring (the push is a plant parameter).
    """Catches compiled pendulum scenes that differ from in process or fall back to Python."""
    scene = get_scene(name)
    fast = simulate(scene.system, mode="compiled")
    with python_slaves():   # every slave through its Python step, not the kernels
        slow = simulate(scene.system, mode="inprocess")
    assert fast.error is None and fast.mode == "compiled" and fast.extra["python_steps"] == 0
    _same_rows(fast, slow)
    assert len(fast.time) == 5001


def test_a_pendulum_falling_in_the_compiled_loop_stops_with_the_in_process_message():
    # At 0.5 V the drives cannot catch the 5 degree release: the robot falls near t = 0.56 s.
    """Catches a compiled fall at another step or with another message."""
    scene = _with(_with(get_scene("pendulum_balance"), "ctrl", v_battery=0.5), "drive_l", v_max=0.5)
    scene = _with(_short(scene, 1.0), "drive_r", v_max=0.5)
    fast = run_scene(scene, mode="compiled")
    with python_slaves():   # every slave through its Python step, not the kernels
        slow = run_scene(scene, mode="inprocess")
    assert "the robot fell over (pitch beyond 90 degrees)" in str(slow.result.error)
    assert fast.result.error == slow.result.error and fast.metrics["mode"] == "compiled"
    assert fast.metrics["completed"] is False and fast.metrics["python_steps"] == 0
    assert 100 < len(fast.result.time) < 1001
    _same_rows(fast.result, slow.result)
