"""The words of a call-limit refusal (:meth:`fmus.slave.budget.CallBudget.require`): what the
step needs, against what one call may take or what is left of it, and the advice only when
one is given ('<cause> needs <count> <what> (~<unit> each), more than <limit>; <advice>')."""
from __future__ import annotations

import pytest

from fmus.slave import budget
from fmus.slave.budget import CallBudget, CallLimitError

UNIT = 1e-3          # 1 ms a unit: CALL_CPU_SECONDS / UNIT units fit a fresh call


def test_a_refusal_without_advice_ends_with_the_limit_and_no_separator():
    """Catches the advice's '; ' written from another argument (a refusal given no advice
    ending in '; <what>')."""
    fits = budget.per_call(UNIT)
    with pytest.raises(CallLimitError) as refused:
        CallBudget().require(fits + 1, UNIT, "evaluations", "this step")
    assert str(refused.value) == (f"this step needs {fits + 1} evaluations (~1 ms each), more than the {fits} "
                                  f"one call may take (~{budget.CALL_CPU_SECONDS:g} s of CPU)")


def test_a_refusal_with_advice_appends_it_after_a_semicolon():
    fits = budget.per_call(UNIT)
    with pytest.raises(CallLimitError) as refused:
        CallBudget().require(fits + 1, UNIT, "evaluations", "this step", "take a smaller step")
    assert str(refused.value).endswith(f"more than the {fits} one call may take "
                                       f"(~{budget.CALL_CPU_SECONDS:g} s of CPU); take a smaller step")


def test_a_spent_budget_names_what_is_left_and_the_count_that_fits_is_accepted():
    """After spending half, half the units fit (floor of left / unit): that many pass, one
    more is refused naming what is left, not the whole call's limit."""
    call = CallBudget()
    call.spend(call.total / 2)
    assert not call.fresh
    half = call.count_left(UNIT)
    assert half == int(budget.CALL_CPU_SECONDS / 2 / UNIT)
    call.require(half, UNIT, "steps", "this step")            # fits: nothing raised
    with pytest.raises(CallLimitError) as refused:
        call.require(half + 1, UNIT, "steps", "this step")
    assert str(refused.value).endswith(f"more than the {half} left of this call's ~{budget.CALL_CPU_SECONDS:g} s "
                                       "of CPU (the rest went to the other components)")


def test_nothing_is_left_once_more_than_the_budget_is_spent():
    call = CallBudget()
    call.spend(2 * call.total)
    assert call.count_left(UNIT) == 0
