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


PLANTS = [("WheeledPendulum", {"tau_l": 0.05, "tau_r": -0.02, "psi0": 0.1}),
          ("FiveBarPlant", {"kernel": "fast", "method": "rk4"}),
          ("FiveBarPlant", {"kernel": "general", "method": "rk4", "gravity_y": -9.81}),
          ("ActuatedFiveBarPlant", {"kernel": "fast", "method": "rk4", "mode": "current"}),
          ("SpecPlant:bench_5r", {"method": "rk4"})]


@pytest.mark.parametrize("model, parameters", PLANTS, ids=["wheeled", "fivebar_fast", "fivebar_general",
                                                           "actuated_fast", "specplant"])
def test_an_rk4_step_fits_exactly_what_is_left_and_half_an_evaluation_less_refuses_it_naming_the_count(
        model, parameters, tmp_path):
    """Seed 4101's survivor [85] (parcosim_wheeledpendulum.py:125, the count ``4 * substeps``
    -> ``4`` passed: no step with 3 substeps met a budget between 4 and 12 evaluations).  At 3
    substeps a step needs 12 evaluations: with exactly 12 left it runs and spends them all;
    with 11.5 left it is refused before any work, naming 12 (4 a substep) and the 11 that are
    left, the state and the time kept.  Every RK4 plant slave; also catches ``<=`` -> ``<`` in
    the fit and a count of one evaluation a substep."""
    from tests.fmus.slave.test_call_limits import plant_slave, sim_of

    slave = plant_slave(model, {**parameters, "substeps": 3}, tmp_path)
    sim = slave.sim if model == "WheeledPendulum" else sim_of(slave)
    unit = budget.WHEELED_RK4_EVALUATION if model == "WheeledPendulum" else budget.plant_work(sim)[0]
    known = 4 * 3
    assert slave.known_step_work() == pytest.approx(known * unit, rel=1e-12)
    y, t = sim.y.copy(), sim.time
    with budget.call_budget() as call:
        call.left = (known - 0.5) * unit       # floor: 11 whole evaluations left
        with pytest.raises(budget.CallLimitError) as refused:
            slave.step(0.0, H)
    words = str(refused.value)
    assert words.startswith(f"step size h = {H!r} s at t = 0.0 s needs {known} right-hand-side evaluations ")
    assert f"more than the {known - 1} left of this call's ~1 s of CPU (the rest went to the other components)" \
           in words
    assert words.endswith("; take shorter steps or use fewer substeps")
    assert np.array_equal(sim.y, y) and sim.time == t
    with budget.call_budget() as call:
        call.left = known * unit               # exactly the step's count: it fits
        slave.step(0.0, H)
        assert call.left == pytest.approx(0.0, abs=1e-6 * unit)
    assert not np.array_equal(sim.y, y)
