"""The times in fmus/cosim/master.py's :class:`Result`: ``wall_s`` is the stepping only (from the
first communication point to the last), ``init_s`` the loading and the initialisation, so a run
refused in its initialisation stepped for exactly no time; a run stopped between steps names
the time of its last row."""
from __future__ import annotations

from dataclasses import replace

import pytest

from fmus.cosim.master import simulate
from fmus.status import RunStatus
from scenarios.scenes.catalogue import get_scene


@pytest.mark.parametrize("mode", ["inprocess", "compiled"])
def test_a_run_refused_in_its_initialisation_stepped_for_no_time(mode):
    """A parameter word for a Real stops the run in the initialisation, before the first
    communication point: no stepping happened, so ``wall_s`` is exactly 0 (the Outcome's
    default), while the time spent loading and initialising is kept in ``init_s``.  Catches a
    non-zero default of the stepping time (training seed 4213 [5])."""
    system = get_scene("bench_circle_PDq").system
    components = tuple(replace(c, parameters={**c.parameters, "T": "fast"}) if c.name == "drive1" else c
                       for c in system.components)
    result = simulate(replace(system, components=components, stop_time=0.01), mode=mode)
    assert result.error.kind == RunStatus.REFUSED and len(result.time) == 0
    assert result.wall_s == 0.0
    assert result.init_s > 0.0


def test_a_completed_run_has_both_a_stepping_and_an_initialisation_time():
    """A completed run took time in both phases, each measured apart (neither is the other's
    copy: the stepping of 50 steps is not the initialisation)."""
    system = get_scene("bench_circle_PDq").system
    result = simulate(replace(system, stop_time=0.05), mode="inprocess")
    assert result.completed and len(result.time) == 51
    assert result.wall_s > 0.0 and result.init_s > 0.0


class _StopAt:
    """A progress callback that interrupts the run (as SIGINT does) once ``fraction`` of it is done."""

    def __init__(self, fraction):
        self.fraction = fraction

    def __call__(self, done):
        if done >= self.fraction:
            raise KeyboardInterrupt


@pytest.mark.parametrize("mode", ["inprocess", "compiled"])
def test_a_run_interrupted_between_steps_names_the_time_of_its_last_row(mode):
    """An interruption after about half the steps keeps the rows done and reports the time of
    the last of them, ``(rows - 1) * h`` (the first row is t = 0), in its record and its message.
    Catches the time of a row that was never made (training seed 4213 [11]: ``rows + 1``)."""
    system = replace(get_scene("bench_circle_PDq").system, stop_time=0.1)
    result = simulate(system, mode=mode, progress=_StopAt(0.5))
    assert result.interrupted and result.error.kind == RunStatus.INTERRUPTED
    last = result.time[-1]
    assert 0.0 < last < system.stop_time
    assert result.error.time == pytest.approx(last, rel=1e-12, abs=1e-15)
    assert result.error.message == f"interrupted at t = {last:.6g} s"


@pytest.mark.parametrize("loop", ["compiled", "python"])
def test_a_stepping_loop_charges_no_initialisation_time_of_its_own(loop):
    """The loops step a stepper their caller initialised: their Outcome has every row, a
    stepping time, and an initialisation time of exactly 0 (the default the master then
    replaces with the time it measured around ``initialize``; training seed 4213 [5], a
    default of 1 s would be added to every run's ``init_s``)."""
    from fmus.cosim.compiled import Plan, run_compiled
    from fmus.cosim.context import RunContext
    from fmus.cosim.master import _close, _instantiate, _step_in_python, stepping_order
    from fmus.cosim.stepper import Stepper

    system = replace(get_scene("bench_circle_PDq").system, stop_time=0.02)
    instances = _instantiate(system, "inprocess", None)
    try:
        order = stepping_order(system, {n: i.variables for n, i in instances.items()})
        stepper = Stepper(system, instances, order)
        stepper.initialize(0.0)
        if loop == "compiled":
            outcome = run_compiled(RunContext(system, "compiled"), stepper, Plan(system, stepper))
        else:
            outcome = _step_in_python(RunContext(system, "inprocess"), stepper)
    finally:
        _close(instances)
    assert outcome.error is None and len(outcome.rows) == system.steps + 1
    assert outcome.wall_s > 0.0 and outcome.init_s == 0.0
