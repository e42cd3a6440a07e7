"""The record fmus/ssp/libcosim.py makes of a step libcosim refused (``_refusal``), and the
annotated copy's destination (``with_libcosim_annotation``): units without running libcosim.

``_refusal`` reads each component's String output ``refusal`` through a last-value observer;
the observer here is a stand-in (libcosimpy's hands ``c_char_p`` values: bytes or None; a
``str`` is taken as it is) so that every kind of value is checked, not only those one FMU
happens to produce.
"""
from __future__ import annotations

from types import SimpleNamespace

import pytest

pytest.importorskip("libcosimpy")

from libcosimpy.CosimEnums import CosimVariableType  # noqa: E402

from fmus.ssp import libcosim  # noqa: E402
from fmus.status import RunError, RunStatus  # noqa: E402

#: A component's refusal record, as its String output holds it.
RECORD = RunError(RunStatus.REFUSED, "input q1 = nan is not finite", instance="ctrl", time=0.25)


class Observer:
    """A last-value observer whose String values are ``values`` (slave index -> value)."""

    def __init__(self, values):
        self.values = values

    def last_string_values(self, index, references):
        assert references == [7]
        return [self.values[index]]


def refusal(monkeypatch, values, message="step failed"):
    """``_refusal`` of two components, ``a`` (index 0) and ``ctrl`` (index 1), whose outputs
    ``refusal`` (reference 7) hold ``values``."""
    from libcosimpy import CosimObserver as module

    monkeypatch.setattr(module.CosimObserver, "create_last_value", staticmethod(lambda: Observer(values)))
    string = SimpleNamespace(type=CosimVariableType.STRING.value, reference=7)
    variables = {"a": {"refusal": string}, "ctrl": {"refusal": string}}
    execution = SimpleNamespace(add_observer=lambda observer: True)
    return libcosim._refusal(execution, {"ctrl": 1, "a": 0}, variables, 0.25, message)


@pytest.mark.parametrize("text", [RECORD.to_json(), RECORD.to_json().encode()])
def test_a_components_refusal_text_is_the_record_whether_bytes_or_str(text, monkeypatch):
    """The first component (by index) whose refusal is not empty names the record: its
    message, instance and time, as bytes (libcosimpy) or as str."""
    error = refusal(monkeypatch, {0: None, 1: text})
    assert error.instance == "ctrl" and error.time == 0.25 and "input q1 = nan is not finite" in str(error)
    assert error.kind is RunStatus.REFUSED


@pytest.mark.parametrize("empty", [None, "", b""])
def test_without_a_refusal_text_libcosims_message_is_the_record(empty, monkeypatch):
    """No component says why (None, "" or b""): libcosim's message and the step's time."""
    error = refusal(monkeypatch, {0: empty, 1: empty}, message=" the slave failed \n")
    assert error.instance is None
    assert str(error) == "libcosim stopped at the step from t = 0.25 s: the slave failed"
