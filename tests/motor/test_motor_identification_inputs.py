"""identify()'s input checks (motor/identification.py), column by column: each refusal names
the column, the entry and its value, and what is required."""
import math

import pytest

from motor import identify

GOOD = dict(u=[1.0, 2.0, 3.5], i=[0.5, 0.6, 0.8], omega=[10.0, 30.0, 55.0])


@pytest.mark.parametrize("change, message", [
    (dict(i="abc"), "i must be a sequence of numbers, got 'abc'"),
    (dict(omega=[[1.0, 2.0], [3.0, 4.0]]), "omega must be one-dimensional, got shape (2, 2)"),
    (dict(u=5.0), "u must be one-dimensional, got shape ()"),
    (dict(i=[0.5, math.inf, math.nan]), "i[1] must be a finite number, got inf"),   # the first one
    (dict(omega=[10.0, math.nan, 55.0]), "omega[1] must be a finite number, got nan"),
    (dict(i=[0.5, 0.6]), "u, i and omega must have the same length, got {'u': 3, 'i': 2, 'omega': 3}"),
    (dict(u=[1.0], i=[0.5], omega=[10.0]), "need at least 2 data points, got 1"),
    (dict(omega=[10.0, -0.0, -3.0]), "omega[1] must be > 0 (D.10 holds for omega > 0), got -0.0"),
    (dict(settling_time=0.2, L=-1e-3), "L must be >= 0, got -0.001"),
])
def test_each_bad_input_is_refused_naming_its_column_entry_and_value(change, message):
    """Catches a check that names another column or entry, lets a column through (the length
    check inverted refuses every good call; one left out lets a short column reach the fit), or
    a message without the value."""
    with pytest.raises(ValueError) as caught:
        identify(**{**GOOD, **change})
    assert str(caught.value) == message
    identify(**GOOD)                      # the same call without the change goes through

