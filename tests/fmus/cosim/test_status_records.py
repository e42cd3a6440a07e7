"""fmus.status: an inner component's refusal seen through a system FMU (:func:`refusal_of`), the
record's read-back (:meth:`RunError.from_record`), and the two tables (FMI and exit statuses)
against docs/contract.md's words."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

from fmus.status import EXIT_STATUS, FMI_STATUS, FmiStatus, RunError, RunStatus, refusal_of, step_failed
from tests.support.paths import ROOT


class _Inner(Exception):
    """What a system FMU's core raises: its inner component's error as ``run_error``."""

    def __init__(self, run_error):
        super().__init__(run_error.message)
        self.run_error = run_error


INNER = RunError(RunStatus.REFUSED, "inner message", "drive1", 0.25, "v", 31.5, "V", 3, "BAD_INPUT")


def test_an_inner_refusal_keeps_its_quantity_and_is_named_from_the_outer_instance():
    """Catches an inner component's record whose instance is not ``<outer>.<inner>``, whose
    time is not the inner one, whose quantity is lost or whose message is not the outer slave's."""
    error = refusal_of(_Inner(INNER), RunStatus.REFUSED, "outer message", "loop", 0.5)
    assert error == RunError(RunStatus.REFUSED, "outer message", "loop.drive1", 0.25, "v", 31.5, "V", 3, "BAD_INPUT")


@pytest.mark.parametrize("instance", [None, ""])
def test_an_inner_refusal_without_instance_is_the_outer_instances(instance):
    """Catches an inner record without instance given another name than the outer instance
    (its message, "None", a trailing dot)."""
    inner = RunError(RunStatus.REFUSED, "inner message", instance, None, "q2", 4.0, "rad")
    error = refusal_of(_Inner(inner), RunStatus.INITIALISATION, "outer message", "loop", 0.5)
    assert (error.instance, error.time, error.kind) == ("loop", 0.5, RunStatus.INITIALISATION)
    assert (error.variable, error.value, error.unit, error.message) == ("q2", 4.0, "rad", "outer message")


@pytest.mark.parametrize("outer", [RunStatus.REFUSED, RunStatus.INITIALISATION])
def test_an_inner_interruption_stays_one_and_other_kinds_become_the_outer(outer):
    """Catches an interruption inside a system FMU reported as a refusal, or an inner refusal
    keeping its own kind where the outer slave's (initialisation or step) applies."""
    stopped = RunError(RunStatus.INTERRUPTED, "SIGINT", "plant", 0.1)
    assert refusal_of(_Inner(stopped), outer, "m", "loop", 0.2).kind is RunStatus.INTERRUPTED
    refused = RunError(RunStatus.INITIALISATION, "m", "plant", 0.0)
    assert refusal_of(_Inner(refused), outer, "m", "loop", 0.0).kind is outer


def test_a_record_with_an_instance_and_a_time_keeps_them():
    """Catches the slave's instance or time written over a model's own (a record that names them)."""
    class Modelled(ValueError):
        def record(self):
            return {"instance": "deriv", "time": 0.125, "variable": "x", "value": -1.0, "code": 2}

    error = refusal_of(Modelled("m"), RunStatus.REFUSED, "outer", "loop", 0.5)
    assert (error.instance, error.time, error.variable, error.value, error.code) == ("deriv", 0.125, "x", -1.0, 2)
    assert (error.kind, error.message) == (RunStatus.REFUSED, "outer")


def test_a_record_read_back_ignores_unknown_keys_and_defaults_missing_ones():
    """Catches from_record refusing a key it does not know (a newer writer's), a missing kind
    not read as a refusal, or a missing field not None."""
    error = RunError.from_record({"variable": "tau1", "value": "-inf", "time": 2, "extra": [1, 2]})
    assert error == RunError(RunStatus.REFUSED, "", None, 2.0, "tau1", -math.inf)
    for kind in RunStatus:
        back = RunError.from_record(RunError(kind, "m", "i", 1.5).record())
        assert back == RunError(kind, "m", "i", 1.5) and back.record()["kind"] == kind.value


def test_a_numpy_value_is_written_as_a_json_float():
    """Catches a numpy scalar value or time written as something else than a plain float."""
    record = RunError(RunStatus.REFUSED, "m", time=np.float64(0.5), value=np.float32(0.25)).record()
    assert type(record["time"]) is float and type(record["value"]) is float
    assert (record["time"], record["value"]) == (0.5, 0.25)


def test_step_failed_is_discard_error_and_fatal():
    """Catches a warning taken as a failed call, or a discard, error or fatal taken as a success
    (FMI 2.0: fmi2Discard and worse refuse the call)."""
    for status in (FmiStatus.DISCARD, FmiStatus.ERROR, FmiStatus.FATAL):
        assert step_failed(status) and step_failed(int(status))
    for status in (FmiStatus.OK, FmiStatus.WARNING):
        assert not step_failed(status) and not step_failed(int(status))


def test_the_status_tables_are_docs_contract_tables():
    """Catches an outcome with another FMI or exit status than docs/contract.md's table says (a
    model's refusal must be fmi2Discard: the instance stays usable; 0 only when completed), or an
    outcome missing from a table."""
    text = (ROOT / "docs" / "contract.md").read_text()
    rows = re.findall(r"^\| `(\w+)` \| fmi2(\w+)[^|]*\| (\d+) \|$", text, re.M)
    documented = {RunStatus(word): (FmiStatus[status.upper()], int(code)) for word, status, code in rows}
    assert set(documented) == set(RunStatus)
    assert {k: (FMI_STATUS[k], EXIT_STATUS[k]) for k in RunStatus} == documented


def test_fmi_status_is_the_standards_fmi2_status():
    """Catches an FmiStatus number other than the FMI 2.0 header's (fmpy ships the standard's
    fmi2FunctionTypes.h): a master would read fmi2Discard as an error or fmi2Fatal as unknown."""
    from fmus.native.build import fmi_headers

    text = (fmi_headers() / "fmi2FunctionTypes.h").read_text()
    body = re.search(r"typedef enum \{([^}]*)\} fmi2Status;", text)[1]
    names = [name.strip() for name in body.split(",")]
    assert {f"fmi2{s.name.capitalize()}" if s.name != "OK" else "fmi2OK": s.value for s in FmiStatus} == \
        {name: k for k, name in enumerate(names)}
