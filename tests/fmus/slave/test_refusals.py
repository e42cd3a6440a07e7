"""fmus/slave/refusals.py called directly, every rule at both sides of its bound: each refusal's
message read back word for word (the variable, its value by ``repr``, the bound), the first
offending name of several, and what each rule leaves to the caller (0, negatives, non-finite
values).  The slaves reach these rules only through their FMI calls, whose tests read a part of
the message (issue 31: seed 3501's survivor [67], ``refuse_tiny``'s message dropped)."""
from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from fmus.slave.refusals import (ABSURD, PRESET_VALUE, TINY, motor_preset, refuse_absurd, refuse_absurd_inputs,
                                 refuse_tiny, require_finite, with_overrides)
from motor import get_motor_preset
from motor._checks import BadValue


def _message(call, **values) -> str:
    with pytest.raises(ValueError) as info:
        call(**values)
    return str(info.value)


def test_a_positive_parameter_below_tiny_is_refused_naming_it_its_value_and_the_bound():
    """Catches the message dropped or without the name, the repr of the value or the bound
    (3501's [67]), the bound taken as <= TINY, and 0, negatives or NaN refused here (the
    callers' own checks name those)."""
    for value in (TINY / 2, 5e-324, math.nextafter(TINY, 0.0)):
        assert _message(refuse_tiny, R=value) == \
            f"parameter R = {value!r} is absurdly small: it must be >= 1e-12 (SI units)"
    refuse_tiny(R=TINY, ke=1.0, L=0.0, b=-1.0, mu=math.nan, kt=math.inf)      # none of these is its business
    assert _message(refuse_tiny, R=1.0, kt=1e-13, ke=1e-14) == \
        "parameter kt = 1e-13 is absurdly small: it must be >= 1e-12 (SI units)"      # the first one, in order


def test_an_absurd_parameter_is_refused_on_either_side_naming_it_and_the_bound():
    """Catches |value| compared without abs (a large negative passes), the bound taken as
    >= ABSURD, non-finite values refused here instead of by the caller's checks, and a message
    without the name, the value or the bound."""
    refuse_absurd(a=ABSURD, b=-ABSURD, c=math.inf, d=-math.inf, e=math.nan, f=0.0)
    for value in (math.nextafter(ABSURD, math.inf), -2e6, 1e300):
        assert _message(refuse_absurd, ok=1.0, x=value) == \
            f"parameter x = {value!r} is absurd: |x| must be <= 1e+06 (SI units)"


def test_an_absurd_input_names_its_time_and_is_marked_as_naming_it():
    """Catches the time missing or not in the 6-digit format, the mark ``names_time`` (the
    slave would add a second time) lost, and the bound taken as >= ABSURD."""
    refuse_absurd_inputs(0.25, tau_l=ABSURD, tau_r=-ABSURD)
    with pytest.raises(ValueError) as info:
        refuse_absurd_inputs(0.1234567, tau_l=1.0, tau_r=-3e6)
    assert str(info.value) == "input tau_r = -3000000.0 at t = 0.123457 s is absurd: |tau_r| must be <= 1e+06"
    assert info.value.names_time is True
    with pytest.raises(ValueError, match="input x = inf at t = 2 s"):
        refuse_absurd_inputs(2.0, x=math.inf)          # an input has no other check: inf is absurd


def test_a_non_finite_value_is_named_first_in_order():
    """Catches a finite value refused, the second non-finite value named before the first."""
    require_finite(a=0.0, b=-1e308, c=5e-324)
    assert _message(require_finite, a=1.0, b=math.nan, c=math.inf) == "b = nan is not finite"
    assert _message(require_finite, c=-math.inf) == "c = -inf is not finite"


def test_overrides_replace_only_the_fields_not_at_the_sentinel_and_name_the_slaves_variable():
    """Catches the sentinel -1 taken as a value, an override lost or put on another field, the
    positive rule applied to fields not listed (L = 1e-13 is a legal inductance) or not to those
    listed, a negative value refused without the slave's variable name, and a value the motor's
    own validation refuses named by its field instead of the slave's variable."""
    preset = get_motor_preset("motor1")
    names = {"R": "R2", "L": "L2", "kt": "kt2", "b": "b2"}
    slave = SimpleNamespace(R2=2.5, L2=1e-13, kt2=PRESET_VALUE, b2=0.0)
    params = with_overrides(preset, slave, names, positive=("R", "kt"))
    assert params == preset.with_(R=2.5, L=1e-13, b=0.0)
    assert params.kt == preset.kt and params.ke == preset.ke

    slave.R2 = 1e-13
    assert _message(with_overrides, params=preset, slave=slave, names=names, positive=("R",)) == \
        "parameter R2 = 1e-13 is absurdly small: it must be >= 1e-12 (SI units)"
    slave.R2, slave.b2 = 1.0, -0.5
    with pytest.raises(BadValue) as info:
        with_overrides(preset, slave, names)
    assert (info.value.name, info.value.value) == ("b2", -0.5)
    assert str(info.value) == "parameter b2 = -0.5 is negative (use -1 for the preset's value)"
    slave.b2 = 2e6
    assert _message(with_overrides, params=preset, slave=slave, names=names) == \
        "parameter b2 = 2000000.0 is absurd: |b2| must be <= 1e+06 (SI units)"


def test_a_value_the_motor_refuses_is_renamed_to_the_slaves_variable():
    """R = 0 passes ``refuse_tiny`` (the caller's checks name 0) and is refused by MotorParams'
    own validation, which knows the field as ``R``: the refusal names the slave's variable.
    Catches the renaming lost, and 0 refused as absurdly small."""
    preset = get_motor_preset("motor1")
    with pytest.raises(BadValue) as info:
        with_overrides(preset, SimpleNamespace(R_A=0.0), {"R": "R_A"}, positive=("R",))
    assert (info.value.name, info.value.value) == ("R_A", 0.0)
    assert str(info.value) == "parameter R_A must be > 0, got 0.0"


def test_an_unknown_preset_is_refused_naming_the_string_parameter():
    """Catches the variable's name or the value left out of the message."""
    assert motor_preset(SimpleNamespace(preset="motor1")) == get_motor_preset("motor1")
    message = _message(motor_preset, slave=SimpleNamespace(preset_b="motorX"), var="preset_b")
    assert message.startswith("parameter preset_b = 'motorX': ")
