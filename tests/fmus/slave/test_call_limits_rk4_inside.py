"""A FiveBarPlant's RK4 step inside a counted call (a system FMU's, :func:`fmus.slave.budget.call_budget`)
is charged its right-hand-side evaluations and refused when they do not fit what is left, the
state kept; outside any counted call it runs as it is (its count fits a whole call)."""
from __future__ import annotations

import numpy as np
import pytest

from fmus.slave import budget
from tests.fmus.slave.test_extremes import make_slave

H = 1e-3


def _plant():
    slave = make_slave("FiveBarPlant")
    assert slave.sim.settings.method == "rk4"
    return slave


def test_an_rk4_step_inside_a_counted_call_is_charged_its_evaluations():
    slave = _plant()
    unit, known, _, _ = budget.plant_work(slave.sim)
    with budget.call_budget() as call:
        slave.step(0.0, H)
        assert call.left == pytest.approx(call.total - known * unit, rel=1e-12)


def test_an_rk4_step_that_does_not_fit_what_is_left_is_refused_and_changes_nothing():
    """Catches the step inside a system FMU's call taken as the uncounted one outside any."""
    slave = _plant()
    unit, known, _, _ = budget.plant_work(slave.sim)
    y = slave.sim.y.copy()
    with budget.call_budget() as call:
        call.spend(call.total - 0.5 * known * unit)
        with pytest.raises(budget.CallLimitError):
            slave.step(0.0, H)
    assert np.array_equal(slave.sim.y, y)
    assert budget.active() is None
    slave.step(0.0, H)                                   # outside a counted call: it runs, nothing raised
