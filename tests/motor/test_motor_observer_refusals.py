"""CurrentObserver.estimate's refusals (motor/observer.py), read back whole for both kinds, with
and without the time: a non-finite input named with its value, a bad step length, an estimate
that overflows named with the inputs it came from; the message word for word, the record
(reason, variable, value, unit, code, time, whether the text names the time), the estimate kept."""
from __future__ import annotations

import math

import pytest

import kernels
from motor import CurrentObserver, kernel, motor1

H = 1e-3
#: R << 1 and L tiny: v = 1e308 V gives an estimate (v - ke omega) / R that overflows, both kinds.
OVERFLOWING = motor1.with_(R=1e-3, L=1e-9)


def _observer(kind):
    observer = CurrentObserver(OVERFLOWING, kind)
    observer.estimate(1.0, 0.5, H)
    return observer


@pytest.mark.parametrize("time", [None, 0.25])
@pytest.mark.parametrize("kind", ["static", "dynamic"])
def test_an_estimate_that_overflows_names_the_time_and_both_inputs(kind, time):
    """Catches the diverged message filled with another quantity for an input (the time for
    omega, omega for v), a time named when none was given or missed when it was, and an
    overflowing estimate that is kept."""
    observer = _observer(kind)
    kept = observer.i_hat
    with pytest.raises(kernels.Refused) as caught:
        observer.estimate(1e308, 3.5, H, time=time)
    at = "" if time is None else " at t = 0.25 s"
    assert str(caught.value) == f"the estimate i_hat = inf A{at} is not finite (inputs v = 1e+308 V, omega = 3.5 rad/s)"
    record = caught.value.record()
    assert (record["reason"], record["variable"], record["value"], record["unit"], record["code"], record["time"]) == \
        ("diverged", "i_hat", math.inf, "A", kernel.DIVERGED, time)
    assert bool(caught.value.names_time) == (time is not None)
    assert observer.i_hat == kept


@pytest.mark.parametrize("time", [None, 0.25])
@pytest.mark.parametrize("kind", ["static", "dynamic"])
@pytest.mark.parametrize("v, omega, name, value", [(math.nan, 2.0, "v", math.nan), (1.0, math.inf, "omega", math.inf),
                                                    (-math.inf, math.nan, "v", -math.inf)])
def test_a_non_finite_input_is_named_with_its_value(kind, time, v, omega, name, value):
    """Catches an input check that names the other input, another value, or a unit; the time
    goes to the record, not the text (the FMU slave adds its own)."""
    observer = _observer(kind)
    kept = observer.i_hat
    with pytest.raises(kernels.Refused) as caught:
        observer.estimate(v, omega, H, time=time)
    assert str(caught.value) == f"{name} must be a finite number, got {value!r}"
    record = caught.value.record()
    assert (record["reason"], record["variable"], record["unit"], record["code"], record["time"]) == \
        ("nonfinite_input", name, "", kernel.NONFINITE_INPUT, time)
    assert record["value"] == value or math.isnan(value) and math.isnan(record["value"])
    assert not caught.value.names_time
    assert observer.i_hat == kept


@pytest.mark.parametrize("kind", ["static", "dynamic"])
@pytest.mark.parametrize("h, words", [(math.nan, "h must be a finite number, got nan"), (-H, "h must be > 0, got -0.001"),
                                      (0.0, "h must be > 0, got 0.0")])
def test_a_bad_step_length_is_refused_by_name(kind, h, words):
    """Catches a step length taken without its check (a zero or negative h would give the
    coefficients of a step backwards) or named as another input."""
    observer = _observer(kind)
    kept = observer.i_hat
    with pytest.raises(ValueError) as caught:
        observer.estimate(1.0, 2.0, h)
    assert str(caught.value) == words
    assert observer.i_hat == kept
