"""A sample time T that is zero, negative or not a number is refused at initialisation by every
model with a parameter T, the refusal naming T, its value, the bound and the time (issue 31;
training seed 4361: siblings of the T = MIN_STEP boundary [8], [18] on the other side, T <= 0)."""
from __future__ import annotations

import pytest

from fmus.slave.base import MIN_STEP
from tests.fmus.slave.test_refusals_sample_time import _initialised

#: Each model's rule for a T <= 0, as its setup states it: the drives' builder (> 0), the
#: observer's and the derivator's own check (> 0), the controllers' floor (>= MIN_STEP).
NON_POSITIVE = {
    "DCMotorDrive": "T must be > 0, got {T!r}",
    "ActuatedFiveBarPlant": "T must be > 0, got {T!r}",
    "CurrentObserver": "parameter T = {T!r} s must be > 0",
    "Derivator": "parameter T = {T!r} must be > 0",
    "PositionController": "parameter T = {T!r} s must be >= " + f"{MIN_STEP:g} s",
    "BalanceController": "parameter T = {T!r} s must be >= " + f"{MIN_STEP:g} s",
}


@pytest.mark.parametrize("model", sorted(NON_POSITIVE))
@pytest.mark.parametrize("T", [0.0, -0.0, -1e-3, -1e6])
def test_a_zero_or_negative_sample_time_is_refused_naming_it_and_its_bound(model, T):
    """Catches a lower bound moved onto or past zero (0 < T taken as 0 <= T, T > 0 as T >= 0):
    a T = 0 model then divides by zero or samples every step; the words are read exactly."""
    slave = _initialised(model, T)
    assert slave.error == f"initialisation refused: {NON_POSITIVE[model].format(T=T)} (t = 0 s)"


@pytest.mark.parametrize("model", sorted(NON_POSITIVE))
def test_a_sample_time_that_is_not_a_number_is_refused_naming_it(model):
    """NaN fails every comparison, so a bound written as ``T < MIN_STEP`` alone lets it through;
    each model refuses it at initialisation naming T and nan, at t = 0 s."""
    error = _initialised(model, float("nan")).error
    assert error.startswith("initialisation refused: ") and error.endswith(" (t = 0 s)"), error
    assert "T" in error and "nan" in error, error
