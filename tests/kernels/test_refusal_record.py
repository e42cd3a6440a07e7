"""The refusal record (kernels.Refused): a kernel's code and offending quantity become one
record with the variable, value, unit, time and instance as fields, the slave's message and
the master's error (fmus.cosim.backends.CoSimulationError.run_error) carry it."""
from __future__ import annotations

import math

import pytest

from fmus.status import RunStatus, RunError, refusal_of
from kernels import Reason, Refusal, Refused, refused

REASONS = {3: Reason("BAD_INPUT", ("q1", "q2"), "rad", "input {variable} = {value!r} {unit} at t = {time} s is absurd")}


def test_a_kernel_refusal_becomes_one_record_naming_the_quantity():
    """Catches a refusal record with a wrong variable, unit, code or message."""
    exc = refused(REASONS, Refusal(code=3, index=1, value=2e7), time=0.25)
    assert str(exc) == "input q2 = 20000000.0 rad at t = 0.25 s is absurd"
    assert isinstance(exc, ValueError)
    assert exc.record() == {"instance": None, "time": 0.25, "variable": "q2", "value": 2e7, "unit": "rad", "code": 3,
                            "reason": "BAD_INPUT", "message": str(exc)}


def test_the_slave_fills_in_the_instance_and_the_time_and_keeps_other_errors_bare():
    """Catches a slave record without instance or time, or a plain error given a code or a variable."""
    exc = Refused("x", code=1, reason="R", variable="v", value=math.inf, unit="V")
    error = refusal_of(exc, RunStatus.REFUSED, "x (step from t = 1.5 s)", "drive1", 1.5)
    assert (error.instance, error.time, error.value, error.code, error.reason) == ("drive1", 1.5, math.inf, 1, "R")
    assert str(error) == "x (step from t = 1.5 s)" and error.kind is RunStatus.REFUSED
    bare = refusal_of(ValueError("plain"), RunStatus.INITIALISATION, "initialisation refused: plain", "drive1", 0.0)
    assert (bare.kind, bare.instance, bare.time, bare.variable, bare.code) == (RunStatus.INITIALISATION, "drive1", 0.0,
                                                                               None, None)


def test_the_record_survives_its_json_with_non_finite_values():
    """The slave's String output ``refusal`` is the record's JSON: an infinite or NaN value (a
    diverged model's) must come back as the same float, not be refused by strict JSON."""
    for value in (math.inf, -math.inf, 2e7):
        error = RunError(RunStatus.REFUSED, "m", "plant", 0.25, "q2", value, "rad", 3, "BAD_INPUT")
        assert RunError.from_json(error.to_json()) == error
    nan = RunError.from_json(RunError(RunStatus.REFUSED, "m", time=math.nan, value=math.nan).to_json())
    assert math.isnan(nan.value) and math.isnan(nan.time)     # a hostile importer's doStep(nan, h)
    assert RunError.from_json("") is None


def test_an_unknown_code_is_not_turned_into_a_wrong_record():
    """Catches an unknown kernel code turned into a record naming a wrong quantity."""
    with pytest.raises(KeyError):
        refused(REASONS, Refusal(code=4, index=0, value=1.0))
