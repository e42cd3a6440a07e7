"""The PositionController's integer and grid bounds hit exactly, on both sides (issue 31, session 44:
the out-of-sample survivors were strict/non-strict comparisons at a boundary no test hit).

docs/contract.md: ``delay_steps`` is an Integer parameter 0-100; ``delay_compensation`` and
``velocity_delay_compensation`` are 0-8, "outside 0-8 refused at initialisation by name".  Each
bound is taken, one beyond (and -1) refused at initialisation in the slave's words, naming the
parameter, its value, the range and the time.  ``kt1``, ``kt2`` = 0 (the boundary of "> 0") and an
empty table range (``x_max`` = ``x_min``) are refused the same way.  The delay itself is checked by
its effect: commands applied ``delay_steps`` samples late, the errors not.  In process, the exact
model (no table to build).
"""
from __future__ import annotations

import pytest

from tests.fmus.slave.test_extremes import GOOD, H, make_slave, set_variables

#: (parameter, its documented largest value), docs/contract.md.
BOUNDS = [("delay_steps", 100), ("delay_compensation", 8), ("velocity_delay_compensation", 8)]


def _error(**parameters) -> str:
    return make_slave("PositionController", {"model": "exact", **parameters}).error


@pytest.mark.parametrize("name, most", BOUNDS)
def test_each_delay_parameter_takes_its_documented_range_and_refuses_one_beyond_naming_it(name, most):
    """Catches the upper bound met on the wrong side (``<=`` -> ``<``: the documented largest value
    refused, or one beyond taken), the range's constant changed, or 0 refused."""
    for value in (0, most):
        assert _error(**{name: value}) == "", (name, value)
    for value in (most + 1, -1):
        assert _error(**{name: value}) == (f"initialisation refused: parameter {name} = {value!r} must be an integer "
                                           f"in [0, {most}] (t = 0 s)")


@pytest.mark.parametrize("name", ["kt1", "kt2"])
def test_a_zero_torque_constant_is_refused_naming_it_and_a_tiny_positive_one_as_absurdly_small(name):
    """i_ref = tau / kt: kt = 0 is the boundary of "> 0" (refused as not positive, not as negative);
    kt = 1e-13 is positive and below TINY (refused as absurdly small); kt = 1e-12 (TINY) is taken."""
    assert _error(**{name: 0.0}) == (f"initialisation refused: parameter {name} = 0.0 must be > 0 (or -1 for the "
                                     "motor preset's) (t = 0 s)")
    assert _error(**{name: 1e-13}) == (f"initialisation refused: parameter {name} = 1e-13 is absurdly small: it must "
                                       "be >= 1e-12 (SI units) (t = 0 s)")
    assert _error(**{name: 1e-12}) == ""


@pytest.mark.parametrize("low, high", [("x_min", "x_max"), ("y_min", "y_max")])
def test_an_empty_table_range_is_refused_naming_both_ends_and_a_zero_grid_step(low, high):
    """The table's range must be non-empty (``high`` > ``low``): equal ends are refused naming both,
    and a grid step of 0 is refused naming it (checked before the table is built, whatever the model)."""
    assert _error(**{low: 0.125, high: 0.125}) == (
        f"initialisation refused: parameters {low} = 0.125, {high} = 0.125: the table's range is empty "
        f"({high} must be > {low}) (t = 0 s)")
    assert _error(grid_step=0.0) == "initialisation refused: parameter grid_step = 0.0 m must be > 0 (t = 0 s)"


def _commands(delay_steps: int, steps: int = 6) -> list:
    slave = make_slave("PositionController", {"model": "exact", "delay_steps": delay_steps})
    parameters, inputs = GOOD["PositionController"]
    rows = []
    for k in range(steps):
        # a reference that moves each sample, so that each sample's commands differ
        set_variables(slave, {**inputs, "x_d": inputs["x_d"] + 1e-3 * k}, initialise=False)
        assert slave.do_step(k * H, H), slave.error
        rows.append(((slave.tau1, slave.tau2, slave.i_ref1, slave.i_ref2), (slave.e1, slave.e2)))
    return rows


@pytest.mark.parametrize("n", [1, 3])
def test_the_commands_are_applied_delay_steps_samples_late_and_the_errors_are_not(n):
    """docs/contract.md: tau1, tau2, i_ref1, i_ref2 applied ``delay_steps`` samples after they were
    computed (zero before), e1, e2 undelayed.  Catches the queue's length off by one or ignored."""
    now, late = _commands(0), _commands(n)
    assert [c for c, _ in late] == [(0.0, 0.0, 0.0, 0.0)] * n + [c for c, _ in now[:-n]]
    assert [e for _, e in late] == [e for _, e in now]
    assert len({c for c, _ in now}) == len(now)     # every sample's commands differ: the shift is seen
