"""fmi2SetupExperiment's times (:func:`fmus.slave.base.check_experiment_times`): a stop time, when
given, must be finite and not before the start; each refusal says which of the two it broke."""
from __future__ import annotations

import math

import pytest

from fmus.slave.base import FmiError, check_experiment_times


@pytest.mark.parametrize("stop", [math.inf, -math.inf, math.nan])
def test_a_stop_time_that_is_not_finite_is_refused_as_not_finite(stop):
    with pytest.raises(FmiError) as refused:
        check_experiment_times(0.0, stop)
    assert str(refused.value) == f"stopTime = {stop!r} s is not finite; nothing was set"


def test_a_stop_time_before_the_start_is_refused_naming_the_start():
    with pytest.raises(FmiError) as refused:
        check_experiment_times(1.0, 0.5)
    assert str(refused.value) == "stopTime = 0.5 s is before startTime = 1.0 s; nothing was set"


@pytest.mark.parametrize("stop", [None, 1.0, 2.5])
def test_no_stop_time_or_one_at_or_after_the_start_is_accepted(stop):
    check_experiment_times(1.0, stop)
