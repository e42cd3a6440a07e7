"""scenarios/scenes/twin.py's parameter bounds hit exactly (issue 31, session 44: boundaries of the
generalised training sample): each of the six free parameters takes both ends of its closed
range, and the next float beyond either end is refused naming the parameter, its value, its
range, unit and meaning."""
from __future__ import annotations

import math

import pytest

from scenarios.scenes.twin import PARAMETERS, Twin


@pytest.mark.parametrize("name", list(PARAMETERS))
def test_each_parameter_takes_both_ends_of_its_range_and_no_float_beyond(name):
    """Catches a strict comparison at either end, and a refusal naming another parameter or range."""
    bound = PARAMETERS[name]
    for value in (bound.low, bound.high):
        assert getattr(Twin(**{name: value}), name) == value
    for value in (math.nextafter(bound.low, -math.inf), math.nextafter(bound.high, math.inf)):
        with pytest.raises(ValueError) as refused:
            Twin(**{name: value})
        assert str(refused.value) == (f"twin parameter {name} = {value!r} must be in [{bound.low:g}, {bound.high:g}] "
                                      f"{bound.unit} ({bound.meaning})")


def test_a_value_that_is_not_a_finite_number_is_refused_by_name():
    for value in (math.nan, math.inf, "1.0", None):
        with pytest.raises(ValueError, match=rf"^twin parameter friction_scale = {value!r} must be in \[0.5, 4\] 1 "):
            Twin(friction_scale=value)
