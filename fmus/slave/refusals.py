"""Refusals of parameter and input values, shared by the slaves: non-finite, absurd and absurdly
small values, and the motor parameters a slave overrides (docs/extremes.md).

Each raises ValueError (or :class:`motor._checks.BadValue`) naming the variable and its value;
the slave's base (:mod:`fmus.slave.base`) turns it into a logged refusal.
"""
from __future__ import annotations

import math

from kernels import timed


class FmiError(Exception):
    """Refuse the current FMI call with ``fmi2Error``.

    parcosim's FMI wrapper (``fmus/export/wrapper/parcosim_fmi2.c``) turns this exception, raised
    in any callback of a slave, into ``fmi2Error`` and logs its message alone (category
    ``logStatusError``); any other exception, ``KeyboardInterrupt`` included, also becomes
    ``fmi2Error``, logged as ``<Type>: <message>``.  The instance stays valid: the importer
    may go on calling it or free it.  (Under pythonfmu's own binary any exception is
    ``fmi2Fatal``.)
    """


#: Start value of a numeric parameter meaning "the preset's value".
PRESET_VALUE = -1.0

#: A numeric parameter beyond this magnitude (SI units) is refused as absurd: no quantity of
#: the robot, its drives or its controller comes near it, and beyond it the models' products
#: overflow, their designs fail without naming the culprit or their loops never end
#: (docs/extremes.md).
ABSURD = 1e6

#: A parameter that must be > 0 (a resistance, a torque constant, a frequency) is refused
#: below this (SI units): its reciprocal, which the models use, would overflow or be absurd.
TINY = 1e-12


def motor_preset(slave, var: str = "preset"):
    """The :class:`motor.MotorParams` preset the slave's String parameter ``var`` names; an
    unknown name is refused as ``parameter <var> = '<name>': ...``."""
    from motor import get_motor_preset

    name = getattr(slave, var)
    try:
        return get_motor_preset(name)
    except ValueError as exc:
        raise ValueError(f"parameter {var} = {name!r}: {exc}") from None


def with_overrides(params, slave, names, positive=()):
    """``params`` (a validated :class:`motor.MotorParams`) with the slave's parameters that
    are not PRESET_VALUE replacing its fields.

    Parameters
    ----------
    params : motor.MotorParams
        The preset's parameters.
    slave : GuardedSlave
        Holds one FMU variable per field named in ``names``.
    names : dict
        Field -> FMU variable (:func:`fmus.slave.declarations.motor_variables`).
    positive : collection of str
        Fields refused below :data:`TINY`.

    Raises
    ------
    motor._checks.BadValue
        Naming the FMU variable and its value, as fields and in the message
        ``"parameter <variable> ..."``: a negative value other than the sentinel, or a
        value the dataclass's own validation refuses (renamed from its field).
    ValueError
        For an absurd value, or one below :data:`TINY` of a field in ``positive``.
    """
    from motor._checks import BadValue     # params is a MotorParams: motor is loaded

    changes = {}
    for field, var in names.items():
        value = float(getattr(slave, var))
        if value == PRESET_VALUE:
            continue
        if value < 0.0:
            raise BadValue(var, value, "parameter {name} = {value!r} is negative (use -1 for the preset's value)")
        refuse_absurd(**{var: value})
        if field in positive:
            refuse_tiny(**{var: value})
        changes[field] = value
    try:
        return params.with_(**changes)
    except BadValue as exc:     # named as the slave's variable
        raise exc.renamed(names, prefix="parameter ") from None


def require_finite(**values) -> None:
    """Raise ValueError naming the first non-finite value."""
    for name, value in values.items():
        if not math.isfinite(value):
            raise ValueError(f"{name} = {value!r} is not finite")


def refuse_absurd(**values) -> None:
    """Raise ValueError naming the first parameter whose magnitude exceeds :data:`ABSURD`
    (non-finite values pass: the caller's own checks name them)."""
    for name, value in values.items():
        if math.isfinite(value) and abs(value) > ABSURD:
            raise ValueError(f"parameter {name} = {value!r} is absurd: |{name}| must be <= {ABSURD:g} (SI units)")


def refuse_absurd_inputs(time: float, **inputs) -> None:
    """Raise ValueError naming the first input beyond :data:`ABSURD` (SI units), its value and
    the time (the wheeled pendulum's torques and sensors: none comes near it)."""
    for name, value in inputs.items():
        if abs(value) > ABSURD:
            raise timed(ValueError(f"input {name} = {value!r} at t = {time:.6g} s is absurd: "
                                   f"|{name}| must be <= {ABSURD:g}"))


def refuse_tiny(**values) -> None:
    """Raise ValueError naming the first parameter (that must be > 0) in (0, :data:`TINY`): the
    caller's own checks name 0 and negative values."""
    for name, value in values.items():
        if math.isfinite(value) and 0.0 < value < TINY:
            raise ValueError(f"parameter {name} = {value!r} is absurdly small: it must be >= {TINY:g} (SI units)")
