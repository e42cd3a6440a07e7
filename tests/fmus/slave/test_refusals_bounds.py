"""Every overridable plant chain and motor parameter at the edges of what it accepts
(fmus/slave/declarations.py ``_chain_overrides``, fmus/slave/refusals.py ``with_overrides``):
-1 (the preset's value), 0, a value under TINY, TINY, a negative value, NaN and an absurd one,
each refusal's message word for word, each accepted value in its own field and nowhere else.

The bounds are the declarations' own descriptions (CHAIN_PARAMETERS: link lengths "> 0", the
rest not negative; motor.presets.POSITIVE_FIELDS for the motor), read here independently of
the code that enforces them.
"""
from __future__ import annotations

import math
from dataclasses import fields as dataclass_fields
from dataclasses import replace
from types import SimpleNamespace

import pytest

from fmus.slave.declarations import CHAIN_PARAMETERS, MOTOR_PARAMETERS, _chain_overrides, motor_variables
from fmus.slave.refusals import ABSURD, PRESET_VALUE, TINY, with_overrides
from motor._checks import BadValue
from motor.presets import MOTOR_PRESETS, POSITIVE_FIELDS
from plant import get_preset

CHAIN = get_preset("thesis_sim").chain1
#: A chain field must be > 0 when its description says so (the link lengths).
LENGTHS = {f for f, text in CHAIN_PARAMETERS if "> 0" in text}
PRESET = "(or -1 for the preset's value)"


def _chain_slave(k: int, **values) -> SimpleNamespace:
    every = {f"chain{k}_{f}": PRESET_VALUE for f, _ in CHAIN_PARAMETERS}
    return SimpleNamespace(**{**every, **values})


def test_the_bounds_read_from_the_descriptions_are_the_link_lengths():
    assert LENGTHS == {"l1", "l2"}


@pytest.mark.parametrize("k", [1, 2])
@pytest.mark.parametrize("field", [f for f, _ in CHAIN_PARAMETERS])
def test_a_chain_parameter_is_taken_in_its_field_or_refused_by_its_bound(field, k):
    """Catches a bound applied to the wrong fields (a mass refused at 0, a length taken at 0
    or below TINY), a refusal naming another variable or bound, and a value put in another
    field (or the preset's value kept)."""
    var = f"chain{k}_{field}"
    assert _chain_overrides(CHAIN, _chain_slave(k), k) == CHAIN
    for value in (0.25, TINY) + (() if field in LENGTHS else (0.0, TINY / 2)):
        assert _chain_overrides(CHAIN, _chain_slave(k, **{var: value}), k) == replace(CHAIN, **{field: value})
    bound = "> 0" if field in LENGTHS else ">= 0"
    for value in (-0.5, -2.0) + ((0.0, TINY / 2) if field in LENGTHS else ()):
        with pytest.raises(ValueError, match=f"^parameter {var} = {value!r} must be {bound} "
                                             rf"\(or -1 for the preset's value\)$"):
            _chain_overrides(CHAIN, _chain_slave(k, **{var: value}), k)
    with pytest.raises(ValueError, match=f"^{var} = nan is not finite$"):
        _chain_overrides(CHAIN, _chain_slave(k, **{var: math.nan}), k)
    with pytest.raises(ValueError, match=rf"^parameter {var} = {2 * ABSURD!r} is absurd: \|{var}\| must be <= "):
        _chain_overrides(CHAIN, _chain_slave(k, **{var: 2 * ABSURD}), k)


MOTOR = MOTOR_PRESETS["motor1"]
NAMES = motor_variables("2")


def _motor_slave(**values) -> SimpleNamespace:
    return SimpleNamespace(**{**{var: PRESET_VALUE for var in NAMES.values()}, **values})


@pytest.mark.parametrize("field", sorted(NAMES))
def test_a_motor_parameter_is_taken_in_its_field_or_refused_by_name(field):
    """Catches an override read from another variable or put in another field, a negative
    value taken, a positive field's value under TINY taken (or TINY itself refused), and a refusal naming the
    dataclass's field rather than the FMU's variable."""
    var = NAMES[field]
    assert with_overrides(MOTOR, _motor_slave(), NAMES, POSITIVE_FIELDS) == MOTOR
    value = 2.5 * getattr(MOTOR, field) + 0.125
    assert with_overrides(MOTOR, _motor_slave(**{var: value}), NAMES, POSITIVE_FIELDS) == MOTOR.with_(**{field: value})
    with pytest.raises(BadValue, match=rf"^parameter {var} = -0.5 is negative \(use -1 for the preset's value\)$"):
        with_overrides(MOTOR, _motor_slave(**{var: -0.5}), NAMES, POSITIVE_FIELDS)
    with pytest.raises(ValueError, match=rf"^parameter {var} = {3 * ABSURD!r} is absurd"):
        with_overrides(MOTOR, _motor_slave(**{var: 3 * ABSURD}), NAMES, POSITIVE_FIELDS)
    if field in POSITIVE_FIELDS:
        with pytest.raises(ValueError, match=f"^parameter {var} = {TINY / 4!r} is absurdly small: it must be >= "):
            with_overrides(MOTOR, _motor_slave(**{var: TINY / 4}), NAMES, POSITIVE_FIELDS)
        assert with_overrides(MOTOR, _motor_slave(**{var: TINY}), NAMES, POSITIVE_FIELDS) == MOTOR.with_(**{field: TINY})
        with pytest.raises(BadValue, match=f"^parameter {var} "):      # 0: the dataclass's refusal, renamed
            with_overrides(MOTOR, _motor_slave(**{var: 0.0}), NAMES, POSITIVE_FIELDS)
    else:
        assert with_overrides(MOTOR, _motor_slave(**{var: 0.0}), NAMES, POSITIVE_FIELDS) == MOTOR.with_(**{field: 0.0})


def test_every_motor_variable_names_a_field_of_the_motor():
    """Catches MOTOR_PARAMETERS naming a field the dataclass does not have (its override
    would be refused as an unknown keyword, not by its variable)."""
    assert {f for f, _, _ in MOTOR_PARAMETERS} <= {f.name for f in dataclass_fields(MOTOR)}
