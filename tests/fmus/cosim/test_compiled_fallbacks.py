"""The compiled mode's choices and the master's reported times (fmus/cosim/master.py,
compiled_adapters.py): every plant setting the compiled loop does not step (an adaptive
integrator, the general kernel, the projection) falls back to in process with its reason and
the in-process rows, the plant's default settings do not; and a run's ``init_s`` is the loading
plus the initialisation, disjoint from the stepping's ``wall_s`` and the plan's ``compile_s``,
all within the call's own wall time (issue 31: seed 3501's survivors [59], the compiled mode's
``init_s`` as a sum of two clock readings, and [75], the plant check's ``kernel != "fast"``
inverted)."""
from __future__ import annotations

import time
import warnings
from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim import master
from fmus.cosim.master import simulate
from fmus.cosim.stepper import Stepper
from scenarios.scenes.catalogue import get_scene


def _system(stop_time=0.02, **plant):
    system = get_scene("bench_circle_PDq").system
    components = tuple(replace(c, parameters={**c.parameters, **plant}) if c.name == "plant" else c
                       for c in system.components)
    return replace(system, components=components, stop_time=stop_time)


def _rows(result, system):
    return np.column_stack([result[s] for s in system.record])


@pytest.mark.parametrize("setting, text", [
    ({"kernel": "general"}, "method='rk4', kernel='general', project=False"),
    ({"project": True}, "method='rk4', kernel='fast', project=True"),
    ({"method": "dopri5"}, "method='dopri5', kernel='fast', project=False"),
])
def test_each_plant_setting_without_a_compiled_step_falls_back_naming_it(setting, text):
    """Catches a setting's test inverted or dropped (the general kernel or the projection run
    by the compiled loop's fast RK4 step, other rows than the settings ask for), the reason
    without the setting's value, and the fallback's rows not those of the in-process run."""
    system = _system(**setting)
    with pytest.warns(UserWarning, match="running in process instead") as caught:
        fast = simulate(system, mode="compiled")
    reason = f"component plant: the plant's settings {text} are not compiled (rk4, fast, no projection are)"
    assert fast.mode == "inprocess" and fast.error is None and fast.extra["fallback"] == reason
    assert [str(w.message) for w in caught] == [f"compiled mode: {reason}; running in process instead"]
    assert np.array_equal(_rows(fast, system), _rows(simulate(system, mode="inprocess"), system))


def test_the_plants_default_settings_run_compiled_without_a_warning():
    """rk4, the fast kernel, no projection: the compiled loop's own step.  Catches the plant
    check refusing its own settings (every compiled run would fall back)."""
    system = _system()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = simulate(system, mode="compiled")
    assert result.mode == "compiled" and "fallback" not in result.extra and result.extra["python_steps"] == 0


@pytest.mark.parametrize("mode", ["inprocess", "compiled"])
def test_init_s_is_the_loading_and_the_initialisation_and_no_more(monkeypatch, mode):
    """Loading made 0.2 s and initialising 0.3 s slower: ``init_s`` holds both, and with the
    stepping's ``wall_s`` (and the compiled plan's ``compile_s``) fits in the call's own wall
    time.  Catches a duration taken as a sum or a reversed difference of clock readings
    (3501's [59]), the loading or the initialisation left out, and the initialisation counted
    in the stepping."""
    instantiate, initialize = master._instantiate, Stepper.initialize

    def slow_instantiate(*args, **kwargs):
        time.sleep(0.2)
        return instantiate(*args, **kwargs)

    def slow_initialize(self, *args, **kwargs):
        time.sleep(0.3)
        return initialize(self, *args, **kwargs)

    monkeypatch.setattr(master, "_instantiate", slow_instantiate)
    monkeypatch.setattr(Stepper, "initialize", slow_initialize)
    system = _system()
    start = time.perf_counter()
    result = simulate(system, mode=mode)
    elapsed = time.perf_counter() - start
    assert result.mode == mode and result.error is None
    compile_s = result.extra.get("compile_s", 0.0)
    # 20 steps take milliseconds; 0.3 s leaves room for a loaded machine and still catches
    # the 0.3 s initialisation counted in the stepping.
    assert 0.5 <= result.init_s and 0.0 < result.wall_s < 0.3 and compile_s >= 0.0
    assert result.init_s + compile_s + result.wall_s <= elapsed
    assert ("compile_s" in result.extra) == (mode == "compiled")


def test_an_unstable_drive_inside_the_plant_falls_back_naming_it_and_is_refused_as_in_process():
    """The drives inside the plant (``ActuatedFiveBarPlant``) with an armature time constant
    RK4 cannot follow at the communication step: the compiled loop declines the component
    naming it and the plant's reason, and the run in process is refused as a run in process is.
    Catches the reason lost (seed 3601's survivor [278], a bare NotCompilable) or the
    fallback's refusal not the in-process one."""
    from scenarios.scenes import drives_in_plant

    system = drives_in_plant(get_scene("bench_circle_TCMDx"), substeps=1).system
    components = tuple(replace(c, parameters={**c.parameters, "L1": 2e-4}) if c.model == "ActuatedFiveBarPlant"
                       else c for c in system.components)
    system = replace(system, components=components, stop_time=0.01)
    inproc = simulate(system, mode="inprocess")
    with pytest.warns(UserWarning, match="running in process instead"):
        fast = simulate(system, mode="compiled")
    prefix, words = inproc.error.message.split(": ", 1)               # the master's, then the plant's words
    assert prefix == "plant refused the step from t = 0 s"
    words = words.removesuffix(" (step from t = 0 s)")
    assert "drive on joint 1: RK4 steps of 0.001 s are unstable" in words
    assert fast.mode == "inprocess" and fast.extra["fallback"] == f"component plant: {words}"
    assert fast.error == inproc.error and fast.error.instance == "plant"


@pytest.mark.parametrize("model", ["FiveBarPlant", "ActuatedFiveBarPlant"])
def test_a_plant_adapter_takes_the_python_state_back_whole(model):
    """After a Python step (a declined kernel step, segments handing over) the adapter's state
    must be the slave's whole state: the plant's 14 states and, with drives inside, each drive's
    current after them, as :meth:`plant.actuated.ActuatedPlant.state` lays out z.  Catches a
    current written to another slot (over a plant state) or left stale."""
    import fmus.cosim.compiled_adapters  # noqa: F401 - registers the adapters
    from fmus.cosim.adapter import ADAPTERS
    from fmus.cosim.backends import InProcessInstance

    instance = InProcessInstance(model, "plant")
    instance.enter_initialization({}, 0.0)
    instance.exit_initialization()
    adapter = ADAPTERS[model]("plant", instance.slave, 1e-3)
    actuated = getattr(instance.slave, "actuated", None)
    sim = adapter._sim()
    sim.y = sim.y + np.arange(1.0, 15.0) * 1e-3
    if actuated is not None:
        for n, (_, drive) in enumerate(actuated.drives):
            drive.i = 0.5 + n                 # in the drive's buffer, which the kernel steps
    expected = actuated.state() if actuated is not None else sim.y
    adapter.from_python()
    np.testing.assert_array_equal(adapter.state[:len(expected)], expected)


def test_a_step_size_a_component_refuses_falls_back_with_the_words_of_its_refusal_at_t_0():
    """A controller whose sample time T = 1.5 ms the 1 ms step does not divide: the compiled loop
    declines it with the slave's own step-size refusal at the run's start (t = 0.0 s), word for word
    as the in-process run's refusal of its first step.  Catches the check made at another time (the
    reason then names a time the run never reached) or its words replaced."""
    system = get_scene("bench_circle_PDq").system
    components = tuple(replace(c, parameters={**c.parameters, "T": 1.5e-3}) if c.name == "ctrl" else c
                       for c in system.components)
    system = replace(system, components=components, stop_time=0.01)
    inproc = simulate(system, mode="inprocess")
    with pytest.warns(UserWarning, match="running in process instead"):
        fast = simulate(system, mode="compiled")
    prefix, words = inproc.error.message.split(": ", 1)
    assert prefix == "ctrl refused the step from t = 0 s"
    assert words.startswith("step size h = 0.001 s at t = 0.0 s does not divide the sample time T = 0.0015 s; ")
    assert fast.mode == "inprocess" and fast.extra["fallback"] == f"component ctrl: {words}"
    assert fast.error == inproc.error and fast.error.instance == "ctrl"


def test_compiled_mode_refuses_a_last_communication_point_beyond_the_slaves_latest_time():
    """Catches the compiled check reading the stop time alone, or the step alone (seed 4001's
    survivor [95], ``stop_time + step`` cut to ``step``): the last communication point is
    stop_time + step, and a slave refuses any t + h beyond MAX_TIME, so the loop may start
    only when that point fits (fmus.slave.base.MAX_TIME)."""
    from fmus.cosim import compiled
    from fmus.slave.base import MAX_TIME

    system = _system()
    h = system.step
    # stop time within MAX_TIME but its last point beyond it: refused, naming the stop time
    for stop in (MAX_TIME, MAX_TIME - h / 2):
        with pytest.raises(compiled.NotCompilable, match=rf"stop time {stop!r} s is beyond 1e\+09 s"):
            compiled.check_compilable(replace(system, stop_time=stop), "gauss-seidel", None)
    # the last point on MAX_TIME itself, and any earlier one, compile
    for stop in (MAX_TIME - 4 * h, 0.02):
        assert stop + h <= MAX_TIME
        compiled.check_compilable(replace(system, stop_time=stop), "gauss-seidel", None)
