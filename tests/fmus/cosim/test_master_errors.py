"""How fmus/cosim/master.py reports a run that stopped: a refused initialisation has no rows at
all (not one row of uninitialised memory), and :func:`run_error_of` turns a component's error
into the run's record (its time, its instance, an interruption's message, a call without a
time of its own)."""
from __future__ import annotations

import math
from dataclasses import replace

import pytest

from fmus.cosim.backends import CoSimulationError
from fmus.cosim.master import run_error_of, simulate
from fmus.status import RunError, RunStatus
from scenarios.scenes.catalogue import get_scene


@pytest.mark.parametrize("mode", ["inprocess", "compiled"])
def test_an_initialisation_that_raises_has_no_rows(mode):
    """A parameter the instance cannot even be given (a word for a Real) stops the run in the
    initialisation itself, before the row of t = 0 (a model's own refusal of its parameters is
    reported by the first step, after that row).  Catches such a run returned with a row (of
    uninitialised values, seed 3601's survivor [96]) or without its instance and time, and a
    stepping time reported for a run that took no step (training sample 4252's [29], the
    outcome's default wall time 0.0 -> 1.0)."""
    system = get_scene("bench_circle_PDq").system
    components = tuple(replace(c, parameters={**c.parameters, "T": "fast"}) if c.name == "drive1" else c
                       for c in system.components)
    result = simulate(replace(system, components=components, stop_time=0.01), mode=mode)
    assert (result.error.kind, result.error.instance, result.error.time) == (RunStatus.REFUSED, "drive1", 0.0)
    assert "'fast'" in result.error.message
    assert len(result.time) == 0 and all(len(result[s]) == 0 for s in system.record)
    assert result.wall_s == 0.0


def test_a_components_record_becomes_the_runs_with_the_masters_message():
    """Catches the component's quantity lost, its instance or time replaced when it has them,
    or the message not the master's (instance, time, the component's words)."""
    record = RunError(RunStatus.REFUSED, "q2 = 4 rad is beyond the workspace", "plant", 0.125, "q2", 4.0, "rad")
    error = CoSimulationError("plant", 0.125, record.message, record)
    got = run_error_of(error, False, 0.1)
    assert got == replace(record, message=str(error))
    assert str(error).startswith("plant") and "0.125" in str(error) and record.message in str(error)


def test_an_error_without_a_record_is_a_refusal_at_its_own_time():
    """Catches a bare error (a foreign FMU's) not made a refusal, without its instance, or at
    the last row's time instead of its own."""
    got = run_error_of(CoSimulationError("foreign", 0.25, "fmi2DoStep refused"), False, 0.2)
    assert (got.kind, got.instance, got.time, got.variable) == (RunStatus.REFUSED, "foreign", 0.25, None)


def test_a_call_without_a_time_is_placed_at_the_last_row():
    """Catches an error of a call with no time of its own (setting inputs: NaN) reported at
    NaN, or its message without the instance and the time of the last row."""
    got = run_error_of(CoSimulationError("drive1", math.nan, "setting inputs failed"), False, 0.375)
    assert got.time == 0.375 and got.message == "drive1: setting inputs failed at t = 0.375 s"
    assert (got.kind, got.instance) == (RunStatus.REFUSED, "drive1")


def test_an_interruption_names_the_last_row_and_the_component_that_stopped():
    """Catches SIGINT between steps or inside a component reported as a refusal, or without the
    time of the last row; and a run that was not stopped given an error."""
    assert run_error_of(None, False, 0.5) is None
    between = run_error_of(None, True, 0.5)
    assert between == RunError(RunStatus.INTERRUPTED, "interrupted at t = 0.5 s", time=0.5)
    inside = CoSimulationError("loop", 0.3, "SIGINT", RunError(RunStatus.INTERRUPTED, "SIGINT", "loop.plant", None))
    got = run_error_of(inside, False, 0.25)
    assert got.kind is RunStatus.INTERRUPTED and got.message == "interrupted at t = 0.25 s (loop: SIGINT)"
    assert (got.instance, got.time) == ("loop.plant", 0.3)


@pytest.mark.parametrize("name", ["missing.fmu", "Folder.FMU"])
def test_a_component_given_as_an_fmu_file_that_is_not_there_is_refused_naming_it(tmp_path, name):
    """Catches a component whose FMU file is missing (or is a folder) run, failing later in
    fmpy, or refused without naming the component and the path."""
    (tmp_path / "Folder.FMU").mkdir()
    system = get_scene("bench_circle_PDq").system
    path = str(tmp_path / name)
    components = tuple(replace(c, model=path) if c.name == "drive1" else c for c in system.components)
    with pytest.raises(ValueError) as refused:
        simulate(replace(system, components=components, stop_time=0.01))
    assert str(refused.value) == f"component drive1: no FMU file {path}"
