"""What a plant's step is charged before it runs (:func:`fmus.slave.budget.known_step_work`,
:func:`fmus.slave.budget.plant_work`), against the right-hand sides the step really evaluates.

A system FMU refuses a communication step whose inner steps' least cost exceeds a call's
budget (fmus/systemfmu/cores.py ``inner_work``): a charge above what a step costs refuses
steps that fit; one below lets a hanging step through.  The general kernel's evaluations are
counted here (``forward_dynamics`` calls), independently of the budget's arithmetic.
"""
from __future__ import annotations

import pytest

from fmus.slave import budget
from tests.fmus.slave.test_call_limits import GRAVITY, plant_slave, rhs_calls, sim_of  # noqa: F401 (a fixture)

H = 1e-3
#: The general kernel's plants, each at rk4 with 3 substeps and at dopri5.
PLANTS = [("FiveBarPlant", {"kernel": "general", **GRAVITY}), ("SpecPlant:bench_5r", {}),
          ("ActuatedFiveBarPlant", {"kernel": "general", "mode": "voltage", **GRAVITY})]
SETTINGS = [{"method": "rk4", "substeps": 3}, {"method": "dopri5"}]


def _evaluations(slave, calls, steps: int) -> list:
    """The right-hand sides each of ``steps`` communication steps of ``slave`` evaluates."""
    counts = []
    for k in range(steps):
        before = calls[0]
        assert slave.do_step(k * H, H) is not False, slave.error
        counts.append(calls[0] - before)
    return counts


@pytest.mark.parametrize("settings", SETTINGS, ids=lambda s: f"{s['method']}{s.get('substeps', '')}")
@pytest.mark.parametrize("model, parameters", PLANTS, ids=[m for m, _ in PLANTS])
def test_a_plant_step_is_charged_the_evaluations_it_makes_at_least(model, parameters, settings, rhs_calls,
                                                                   tmp_path):
    """RK4: exactly the evaluations every step makes (4 a substep); dopri5: its first attempt,
    no more than the fewest a step makes, and as many as a step of the plant alone makes once
    settled (a single accepted attempt: Dormand-Prince's 7 stages).  Catches a charge with the
    wrong evaluation count, unit (kernel, method or joints), or substeps."""
    slave = plant_slave(model, {**parameters, **settings}, tmp_path)
    sim = sim_of(slave)
    unit = budget.plant_evaluation_cost("general", settings["method"], budget.joints_of(sim.mechanism))
    assert budget.GENERAL_EVALUATION_BASE < unit     # a mechanism has joints
    counts = _evaluations(slave, rhs_calls, 6)
    charge = slave.known_step_work()
    if settings["method"] == "rk4":
        assert set(counts) == {4 * settings["substeps"]}
        assert charge == pytest.approx(unit * counts[0], rel=1e-12)
        assert budget.plant_work(sim)[1] == counts[0]
    else:
        assert budget.plant_work(sim)[1] is None        # not known before the step
        assert charge <= unit * min(counts) * (1 + 1e-12)
        if model != "ActuatedFiveBarPlant":             # the drives' currents keep dopri5 retrying
            assert charge == pytest.approx(unit * counts[-1], rel=1e-12)


@pytest.mark.parametrize("method, unit", [("rk4", budget.FAST_RK4_EVALUATION),
                                          ("dopri5", budget.FAST_DOPRI5_EVALUATION)])
def test_the_compiled_kernels_step_is_charged_at_the_compiled_unit(method, unit, rhs_calls):
    """The compiled 5R evaluates in C (no ``forward_dynamics`` call): its charge is the same
    count at the compiled unit.  Catches the kernel or the method not passed to the unit."""
    fast = plant_slave("FiveBarPlant", {"kernel": "fast", "method": method, "substeps": 2, **GRAVITY})
    general = plant_slave("FiveBarPlant", {"kernel": "general", "method": method, "substeps": 2, **GRAVITY})
    general_unit = budget.plant_evaluation_cost("general", method, budget.joints_of(sim_of(general).mechanism))
    assert fast.known_step_work() / unit == pytest.approx(general.known_step_work() / general_unit, rel=1e-12)
    assert _evaluations(fast, rhs_calls, 2) == [0, 0]


@pytest.mark.parametrize("kernel, method, advice", [
    ("general", "rk4", "take shorter steps or use fewer substeps"),
    ("general", "dopri5", "take shorter steps, loosen rtol = 1e-06 / atol = 1e-09 or use kernel 'fast'"),
    ("fast", "dopri5", "take shorter steps, loosen rtol = 1e-06 / atol = 1e-09")])
def test_plant_work_names_what_is_counted_and_what_to_change(kernel, method, advice):
    """Catches the words of a refusal naming another kernel or method, or advice that does not
    apply (kernel 'fast' offered to a plant that has it)."""
    slave = plant_slave("FiveBarPlant", {"kernel": kernel, "method": method, "rtol": 1e-6, "atol": 1e-9, **GRAVITY})
    _, _, what, said = budget.plant_work(sim_of(slave))
    assert what == f"right-hand-side evaluations ({kernel} kernel, {method})"
    assert said == advice
