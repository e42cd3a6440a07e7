"""motor/_checks.py, every check at its boundary, its refusal read back field by field and
word for word, and :meth:`BadValue.renamed` with a prefix and with both names renamed."""
from __future__ import annotations

import math

import pytest

from motor import _checks
from motor._checks import BadValue


def refusal(check, *args) -> BadValue:
    with pytest.raises(BadValue) as caught:
        check(*args)
    return caught.value


@pytest.mark.parametrize("value, message", [
    (math.nan, "R must be a finite number, got nan"),
    (-math.inf, "R must be a finite number, got -inf"),
    ("1 ohm", "R must be a finite number, got '1 ohm'"),
    (None, "R must be a finite number, got None"),
])
def test_finite_refuses_what_is_not_a_finite_number_naming_it(value, message):
    """Catches a finite check that lets a non-finite or non-numeric value through, or a message
    that names another variable or value."""
    exc = refusal(_checks.finite, "R", value)
    assert str(exc) == message
    assert (exc.name, exc.other, exc.other_value) == ("R", None, None)
    assert exc.value is value or (isinstance(value, float) and math.isnan(value) and math.isnan(exc.value))


def test_each_check_accepts_its_boundary_and_refuses_just_past_it():
    """Catches a strict comparison made loose or the other way round (``<`` for ``<=``), and a
    check that returns something other than the value as a float or int."""
    assert _checks.finite("x", "2.5") == 2.5 and isinstance(_checks.finite("x", 3), float)
    assert _checks.positive("L", 5e-324) == 5e-324
    assert str(refusal(_checks.positive, "L", 0.0)) == "L must be > 0, got 0.0"
    assert str(refusal(_checks.positive, "L", -1)) == "L must be > 0, got -1"
    assert _checks.non_negative("b", 0.0) == 0.0
    assert str(refusal(_checks.non_negative, "b", -5e-324)) == "b must be >= 0, got -5e-324"
    assert _checks.choice("kind", "luenberger", ("luenberger", "kalman")) == "luenberger"
    assert str(refusal(_checks.choice, "kind", "lqe", ("luenberger", "kalman"))) == \
        "kind must be one of 'luenberger', 'kalman'; got 'lqe'"
    assert _checks.count("n", 0) == 0 and _checks.count("n", 6.0, limit=7) == 6
    assert isinstance(_checks.count("n", 6.0, limit=7), int)


@pytest.mark.parametrize("value, limit, message", [
    (7, 7, "n must be a whole number in [0, 7), got 7"),
    (-1, 7, "n must be a whole number in [0, 7), got -1"),
    (2.5, 7, "n must be a whole number in [0, 7), got 2.5"),
    (True, 7, "n must be a whole number in [0, 7), got True"),
    (2 ** 31, 2 ** 31, "n must be a whole number in [0, 2147483648), got 2147483648"),
    ("three", 7, "n must be a whole number >= 0, got 'three'"),
    (math.inf, 7, "n must be a whole number >= 0, got inf"),
])
def test_count_refuses_what_is_not_a_whole_number_below_the_limit(value, limit, message):
    """Catches a count that accepts its limit, a negative number, a fraction or a bool, or that
    names another limit than the one given (or the default 2**31)."""
    args = ("n", value) if limit == 2 ** 31 else ("n", value, limit)
    assert str(refusal(_checks.count, *args)) == message


def test_renamed_keeps_the_value_and_puts_the_prefix_before_the_message_braces_and_all():
    """Catches a rename that drops the prefix, formats the prefix's braces as fields, leaves a
    name unrenamed, or loses the compared value."""
    exc = BadValue("T", 0.5, "{name} = {value!r} s must be below {other} = {other_value!r} s", "t_end", 0.25)
    renamed = exc.renamed({"T": "sample_time", "t_end": "stop_time"}, prefix="parameter {fmu} ")
    assert str(renamed) == "parameter {fmu} sample_time = 0.5 s must be below stop_time = 0.25 s"
    assert (renamed.name, renamed.value, renamed.other, renamed.other_value) == ("sample_time", 0.5, "stop_time", 0.25)
    kept = exc.renamed({})
    assert str(kept) == str(exc) == "T = 0.5 s must be below t_end = 0.25 s"
    assert str(kept.renamed({"T": "dt"}, prefix="input ")) == "input dt = 0.5 s must be below t_end = 0.25 s"
