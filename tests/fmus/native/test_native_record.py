"""The native FMUs' refusal record (String output ``refusal``, fmus/native/pcn_record.c) is the
pythonfmu twin's JSON byte for byte where the equality scripts (tests/test_native_equality.py)
do not reach: non-ASCII text in the message and the instance name (json.dumps' ensure_ascii:
``\\uXXXX``, a surrogate pair past U+FFFF), a model's quantity with a non-finite value, and the
record kept through "an earlier step was refused" and restored with the FMU state.  Wrong code
it catches: UTF-8 bytes copied into the JSON, a surrogate pair or hex case wrong, a record
overwritten by a repeated refusal, a record that is not FMU state."""
from __future__ import annotations

import json
import math

import numpy as np

from controller.derivators import Derivator
from fmus.native.state_bytes import data_words, with_data_word
from fmus.status import RunError, RunStatus, refusal_of
from tests.support.fmu_calls import Driver

#: A preset name with a Latin letter (U+00F6) and a symbol past U+FFFF (U+1D11E).
PRESET = "m\u00f6tor-\U0001D11E"
INSTANCE = "obs\u00e9rver"


def _both(native_fmus, twin_fmus, model, instance=INSTANCE):
    return Driver(twin_fmus[model], instance), Driver(native_fmus[model], instance)


def _run(driver, calls):
    return [driver.call(*c) for c in calls]


def test_non_ascii_message_and_instance_are_escaped_as_json_dumps_does(native_fmus, twin_fmus):
    """Catches the C record writer escaping non-ASCII text (or a surrogate pair) otherwise than json.dumps,
    so the native and pythonfmu FMUs' records differ or do not parse."""
    twin, native = _both(native_fmus, twin_fmus, "CurrentObserver")
    calls = [("set", {"preset": PRESET}), ("setup", 0.0), ("enter",), ("exit",), ("get", ["refusal", "error"])]
    (a, b) = (_run(d, calls)[-1].result for d in (twin, native))
    assert b == a
    text = b[0]
    assert text.isascii() and "\\u00f6" in text and "\\ud834\\udd1e" in text and "\\u00e9" in text
    error = RunError.from_json(text)
    assert error.kind is RunStatus.INITIALISATION and error.instance == INSTANCE and PRESET in error.message
    assert error.message == b[1] and error.to_json() == text          # json.dumps of the record read back
    twin.close()
    native.close()


def test_a_models_quantity_survives_repeats_and_the_fmu_state(native_fmus, twin_fmus):
    """DCMotorDrive with a NaN omega: the drive kernel's record (variable, "nan", code, reason);
    the next step's "earlier step was refused" keeps it; a state taken before clears it and one
    taken after brings it back."""
    twin, native = _both(native_fmus, twin_fmus, "DCMotorDrive", "drive")
    h = 1e-3
    calls = [("setup", 0.0), ("enter",), ("exit",), ("step", 0.0, h), ("getstate", "before"),
             ("set", {"omega": math.nan}), ("step", h, h), ("get", ["refusal"]), ("getstate", "after"),
             ("step", h, h), ("get", ["refusal"]), ("setstate", "before"), ("get", ["refusal"]),
             ("setstate", "after"), ("get", ["refusal"])]
    twin_trace, native_trace = _run(twin, calls), _run(native, calls)
    reads = [s.result[0] for s in native_trace if s.call[0] == "get"]
    assert reads == [s.result[0] for s in twin_trace if s.call[0] == "get"]
    refused = json.loads(reads[0])
    assert (refused["variable"], refused["value"], refused["reason"], refused["time"]) == (
        "omega", "nan", "nonfinite_input", h)
    assert reads[1] == reads[0] and reads[2] == "" and reads[3] == reads[0]
    assert [s.status for s in native_trace] == [s.status for s in twin_trace]
    twin.close()
    native.close()


def test_a_refusal_at_initialisation_carries_the_kernels_quantity(native_fmus, twin_fmus):
    """A trajectory started at t = -1 s: its kernel refuses the time (bad_time, variable t, the
    model's own time) at initialisation, and says so again at the first step."""
    twin, native = _both(native_fmus, twin_fmus, "Trajectory", "traj")
    calls = [("setup", -1.0), ("enter",), ("exit",), ("get", ["refusal"]), ("step", -1.0, 1e-3), ("get", ["refusal"])]
    twin_trace, native_trace = _run(twin, calls), _run(native, calls)
    assert [(s.status, s.result, s.messages) for s in native_trace] == [
        (s.status, s.result, s.messages) for s in twin_trace]
    record = json.loads(native_trace[3].result[0])
    assert (record["kind"], record["variable"], record["unit"], record["reason"], record["time"]) == (
        "initialisation", "t", "s", "bad_time", -1.0)
    assert native_trace[5].result == native_trace[3].result and native_trace[4].status == 2
    twin.close()
    native.close()


def test_a_damaged_derivator_buffer_is_refused_with_the_twins_record(native_fmus):
    """A state whose model data is all zero (as one taken before set-up, which the state check
    admits) restored into a running native Derivator: its kernel refuses the buffer, and the
    record is the one the twin's own layers make of the same buffer (controller.derivators'
    refusal, fmus.status.refusal_of, the slave's " (step from t = ...)"), byte for byte.
    Catches the refusal written with null fields or in other words (code and word index in
    place of the word's name)."""
    h = 1e-3
    native = Driver(native_fmus["Derivator"], "deriv")
    trace = _run(native, [("setup", 0.0), ("enter",), ("exit",), ("set", {"q1": 0.1, "q2": 0.2}), ("step", 0.0, h),
                          ("getstate", "s"), ("serialize", "s")])
    assert [s.status for s in trace] == [0] * 7
    damaged = native.states["s"]
    for k in range(len(data_words(damaged))):
        damaged = with_data_word(damaged, k, 0.0)
    trace = _run(native, [("bytes", "z", damaged), ("deserialize", "z"), ("setstate", "z"), ("step", h, h),
                          ("get", ["refusal", "error"])])
    assert [s.status for s in trace] == [0, 0, 0, 2, 0]
    twin = Derivator()
    twin.reset([0.0, 0.0])
    twin.buf = np.zeros_like(twin.buf)
    try:
        twin.step_values((0.1, 0.2), 1e6)
    except ValueError as exc:
        message = f"{exc} (step from t = {h:.6g} s)"
        expected = refusal_of(exc, RunStatus.REFUSED, message, "deriv", h).to_json()
    assert trace[-1].result == [expected, message]
    assert json.loads(expected)["reason"] == "bad_layout"
