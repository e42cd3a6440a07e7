"""What a step spends of its call's budget (:func:`fmus.slave.budget.bounded_integration`):
inside a system FMU (a budget active on the thread) a step whose count is known refuses before
any work when it does not fit, naming that count and its unit, and otherwise spends the
count it makes, at its unit: the charge a system FMU reckons with beforehand
(``known_step_work``).  Seed 4001's survivors [51] (``require``'s count and unit swapped)
and [74] (the wheeled pendulum's RK4 step returning 4 evaluations whatever its substeps)."""
from __future__ import annotations

import pytest

from fmus.slave import budget
from fmus.slave.budget import CallLimitError
from tests.fmus.slave.test_call_limits import plant_slave, sim_of

UNIT = 1e-3          # 1 ms a unit: CALL_CPU_SECONDS / UNIT units fit a fresh call


def test_a_known_count_that_does_not_fit_is_refused_naming_the_count_and_its_unit_before_any_work():
    """The words are the count of evaluations and the cost of one (not the two exchanged), the
    cause names the step size and the time, and ``run`` is never called."""
    fits = budget.per_call(UNIT)
    runs = []
    with pytest.raises(CallLimitError) as refused:
        budget.bounded_integration(runs.append, UNIT, fits + 1, "evaluations", 0.25, 0.5, "take shorter steps")
    assert runs == []
    assert str(refused.value).startswith(f"step size h = 0.5 s at t = 0.25 s needs {fits + 1} evaluations "
                                         f"(~1 ms each), more than the {fits} one call may take")
    assert str(refused.value).endswith("; take shorter steps")


def test_a_known_count_that_fits_a_shared_call_is_run_and_spends_its_evaluations():
    """Inside an enclosing call's budget: ``run`` gets no limit and what it returns is spent."""
    with budget.call_budget() as call:      # as a system FMU's step holds it for its members
        assert budget.active() is call
        assert budget.bounded_integration(lambda limit: 7 if limit is None else -1, UNIT, 8, "evaluations",
                                          0.0, 1e-3) == 7
        assert call.left == pytest.approx(call.total - 7 * UNIT, rel=1e-12)


@pytest.mark.parametrize("substeps", [1, 3])
@pytest.mark.parametrize("model, parameters", [
    ("WheeledPendulum", {}),
    ("FiveBarPlant", {"kernel": "fast", "method": "rk4"}),
    ("FiveBarPlant", {"kernel": "general", "method": "rk4", "gravity_y": -9.81}),
    ("ActuatedFiveBarPlant", {"kernel": "general", "method": "rk4", "mode": "voltage"}),
    ("ActuatedFiveBarPlant", {"kernel": "fast", "method": "rk4", "mode": "current"}),
    ("SpecPlant:bench_5r", {"method": "rk4"})],
    ids=["wheeled", "fivebar_fast", "fivebar_general", "actuated_general", "actuated_fast", "specplant"])
def test_an_rk4_plant_step_inside_a_system_spends_four_evaluations_a_substep(model, parameters, substeps, tmp_path):
    """RK4 evaluates its right-hand side 4 times a substep: the step spends that at the
    plant's unit (its kernel's, for its joints), the same as the charge the slave announces
    before it; every plant slave that steps within a budget, at 1 and 3 substeps."""
    slave = plant_slave(model, {**parameters, "substeps": substeps}, tmp_path)
    charge = slave.known_step_work()
    with budget.call_budget() as call:
        assert budget.active() is call
        left = call.left
        assert slave.do_step(0.0, 1e-3) is not False
        spent = left - call.left
    assert spent == pytest.approx(charge, rel=1e-12)
    sim = None if model == "WheeledPendulum" else sim_of(slave)
    unit = budget.WHEELED_RK4_EVALUATION if sim is None else \
        budget.plant_evaluation_cost(parameters.get("kernel", "general"), "rk4", budget.joints_of(sim.mechanism))
    assert spent == pytest.approx(4 * substeps * unit, rel=1e-12)
