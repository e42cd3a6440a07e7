"""fmus/cosim/system.py: a system as data, each refusal by its message and each boundary on
both sides (issue 31: the checks a one-line change would loosen: a comparison turned, a
condition dropped, the other operand named)."""
from __future__ import annotations

import math

import pytest

from fmus.cosim.system import Component, Connection, System, split_signal


def _system(**changes):
    base = {"components": (Component("a", "Derivator"), Component("b", "Trajectory")),
            "connections": (Connection("b.x_d", "a.q1"),), "record": ("a.dq1",), "stop_time": 0.5, "step": 2e-3}
    return System(**{**base, **changes})


@pytest.mark.parametrize("name", ["", "plant.x", "."])
def test_a_component_name_empty_or_with_a_dot_is_refused(name):
    with pytest.raises(ValueError, match=rf"component name {name!r} must be non-empty and contain no '.'"):
        Component(name, "Derivator")


@pytest.mark.parametrize("substeps", [0, -2, 1.0, 2.5, "2"])
def test_sub_steps_must_be_an_integer_of_at_least_one(substeps):
    with pytest.raises(ValueError, match=rf"component c: substeps = {substeps!r} must be an integer >= 1"):
        Component("c", "Derivator", substeps=substeps)


def test_one_sub_step_and_more_are_accepted():
    assert Component("c", "Derivator").substeps == 1 and Component("c", "Derivator", substeps=3).substeps == 3


@pytest.mark.parametrize("signal", ["plant", "plant.", ".x", ""])
def test_a_signal_not_written_instance_dot_variable_is_refused(signal):
    with pytest.raises(ValueError, match=rf"signal {signal!r} must be written 'instance.variable'"):
        split_signal(signal)


def test_a_signal_splits_at_its_first_dot():
    assert split_signal("plant.chain1.l1") == ("plant", "chain1.l1")


def test_the_steps_of_a_run_and_its_boundaries():
    """stop 0.7 s at 2 ms: 350 steps (0.7 / 0.002 is 349.99999999999994 in floating point:
    rounded, not cut); a stop time of 0 is a run of no step; a step of 0, a negative stop,
    NaN are refused naming the value."""
    assert 0.7 / 2e-3 < 350 and _system(stop_time=0.7).steps == 350
    assert _system(stop_time=0.0).steps == 0
    for step in (0.0, -1e-3, math.nan):
        with pytest.raises(ValueError, match=rf"step = {step!r} s must be > 0"):
            _system(step=step)
    for stop in (-1e-9, math.nan):
        with pytest.raises(ValueError, match=rf"stop_time = {stop!r} s must be >= 0"):
            _system(stop_time=stop)


def test_duplicate_names_an_input_connected_twice_and_unknown_instances_are_refused():
    with pytest.raises(ValueError, match=r"duplicate component names: \['a'\]"):
        _system(components=(Component("a", "Derivator"), Component("b", "Trajectory"), Component("a", "Trajectory")))
    with pytest.raises(ValueError, match=r"input a.q1 is connected more than once"):
        _system(connections=(Connection("b.x_d", "a.q1"), Connection("b.y_d", "a.q1")))
    _system(connections=(Connection("b.x_d", "a.q1"), Connection("b.x_d", "a.q2")))    # one output, two inputs
    for where in ({"record": ("a.dq1", "c.x")}, {"connections": (Connection("c.x", "a.q1"),)},
                  {"connections": (Connection("b.x_d", "c.q1"),)}):
        signal = "c.x" if "record" in where or where["connections"][0].source == "c.x" else "c.q1"
        with pytest.raises(ValueError, match=rf"signal '{signal}' names no component \(components: a, b\)"):
            _system(**where)


def test_a_component_is_found_by_name_and_an_unknown_one_is_a_key_error():
    system = _system()
    assert system.component("b") is system.components[1]
    with pytest.raises(KeyError):
        system.component("c")
