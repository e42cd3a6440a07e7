"""The refusal record (kernels.Refused): a kernel's code and offending quantity become one
record with the variable, value, unit, time and instance as fields, the slave's message and
the master's error (fmus.cosim.backends.CoSimulationError.refusal) carry it."""
from __future__ import annotations

import math

import pytest

from fmus.slave.base import _refusal_record
from kernels import Reason, Refusal, Refused, refused

REASONS = {3: Reason("BAD_INPUT", ("q1", "q2"), "rad", "input {variable} = {value!r} {unit} at t = {time} s is absurd")}


def test_a_kernel_refusal_becomes_one_record_naming_the_quantity():
    """Catches a refusal record with a wrong variable, unit, code or message."""
    exc = refused(REASONS, Refusal(code=3, index=1, value=2e7), time=0.25)
    assert str(exc) == "input q2 = 20000000.0 rad at t = 0.25 s is absurd"
    assert isinstance(exc, ValueError)
    assert exc.record() == {"instance": None, "time": 0.25, "variable": "q2", "value": 2e7, "unit": "rad", "code": 3,
                            "reason": "BAD_INPUT", "message": str(exc)}


def test_the_slave_fills_in_the_instance_and_the_time_and_ignores_other_errors():
    """Catches a slave record without instance or time, or one made of a plain error."""
    exc = Refused("x", code=1, reason="R", variable="v", value=math.inf, unit="V")
    record = _refusal_record(exc, "drive1", 1.5)
    assert (record["instance"], record["time"], record["value"]) == ("drive1", 1.5, math.inf)
    assert _refusal_record(ValueError("plain"), "drive1", 1.5) is None


def test_an_unknown_code_is_not_turned_into_a_wrong_record():
    """Catches an unknown kernel code turned into a record naming a wrong quantity."""
    with pytest.raises(KeyError):
        refused(REASONS, Refusal(code=4, index=0, value=1.0))
