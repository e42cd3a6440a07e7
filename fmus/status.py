"""How a run, a step or a sample ended: one vocabulary (:class:`RunStatus`), one record of why
(:class:`RunError`), and one table each to the FMI statuses and to ``parcosim``'s exit statuses.

A refusal is data from the model to the user: a kernel's code becomes
:class:`kernels.Refused` (instance, time, variable, value, unit, code, reason, message); the
slave keeps it as its :meth:`RunError.record` in the String output ``refusal`` (JSON, beside
the message in ``error`` and the FMI log); the master's back ends read that output, in
process and through an FMU alike, and :class:`fmus.cosim.master.Result` carries it as
``error``; ``metrics.json`` writes its fields, a sweep's rows its columns, the CLI its
message.  Nothing on the way reads a message to learn what happened (docs/contract.md,
"Outcomes and errors as data").
"""
from __future__ import annotations

import enum
import json
import math
from dataclasses import asdict, dataclass, fields, replace


class RunStatus(str, enum.Enum):
    """How a run (a step, a sample) ended.  The value is the word written in files."""

    #: The run reached its stop time.
    COMPLETED = "completed"
    #: A component refused a step (its model, its inputs or the call): the run stopped there.
    REFUSED = "refused"
    #: A component refused its initialisation (its parameters): no step was taken.
    INITIALISATION = "initialisation"
    #: SIGINT (Ctrl-C) stopped the run between two steps, or a component inside a call.
    INTERRUPTED = "interrupted"
    #: The run could not be made or its worker died (a sweep's or a report's task): no rows.
    FAILED = "failed"
    #: The command was refused before any work (bad arguments, an output it cannot write).
    INVALID = "invalid"


class FmiStatus(enum.IntEnum):
    """``fmi2Status`` (FMI 2.0, 2.1.3)."""

    OK = 0
    WARNING = 1
    DISCARD = 2
    ERROR = 3
    FATAL = 4
    PENDING = 5


#: The status of the FMI call with which a parcosim FMU reports each outcome of its own: a
#: refused or interrupted ``fmi2DoStep`` is fmi2Discard (FMI 2.0's stepFailed: the instance
#: stays usable, fmi2SetFMUstate goes back); a refused initialisation is reported by the first
#: ``fmi2DoStep`` (fmi2Discard), fmi2ExitInitializationMode itself returns fmi2OK so that tools
#: which abort on any error there still get the reason (docs/extremes.md); a call refused as
#: such (:class:`fmus.slave.refusals.FmiError`: a set of an output, calls out of order) is
#: fmi2Error.
FMI_STATUS = {RunStatus.COMPLETED: FmiStatus.OK, RunStatus.REFUSED: FmiStatus.DISCARD,
              RunStatus.INITIALISATION: FmiStatus.DISCARD, RunStatus.INTERRUPTED: FmiStatus.DISCARD,
              RunStatus.FAILED: FmiStatus.ERROR, RunStatus.INVALID: FmiStatus.ERROR}

#: ``parcosim``'s exit status for each outcome (128 + SIGINT for an interruption, as shells
#: report it; 2 for a command refused before any work, as argparse does).
EXIT_STATUS = {RunStatus.COMPLETED: 0, RunStatus.REFUSED: 1, RunStatus.INITIALISATION: 1, RunStatus.FAILED: 1,
               RunStatus.INTERRUPTED: 130, RunStatus.INVALID: 2}


def step_failed(status: int) -> bool:
    """Whether an FMI call's ``status`` refused it (fmi2Discard, fmi2Error or fmi2Fatal)."""
    return status > FmiStatus.WARNING


@dataclass(frozen=True)
class RunError:
    """Why a run (a step, a sample) stopped: the :class:`RunStatus` (``kind``), the message a user
    reads (``str()``), and, as fields, who refused (``instance``), when (``time`` [s]) and, for
    a model's refusal (:class:`kernels.Refused`), the quantity: ``variable``, ``value``,
    ``unit``, the model's ``code`` and its name ``reason``.  A field nobody knows is None."""

    kind: RunStatus
    message: str
    instance: str | None = None
    time: float | None = None
    variable: str | None = None
    value: float | None = None
    unit: str | None = None
    code: int | None = None
    reason: str | None = None

    def __str__(self) -> str:
        return self.message

    def record(self) -> dict:
        """The fields as a dict of JSON types (``kind`` its word; a non-finite ``value`` or
        ``time``, a diverged model's or a hostile importer's, as the strings ``"inf"``, ``"-inf"``,
        ``"nan"``, which JSON has no numbers for)."""
        out = asdict(self)
        out["kind"] = self.kind.value
        for name in _NUMBERS:
            if out[name] is not None:
                number = float(out[name])        # a numpy scalar too
                out[name] = number if math.isfinite(number) else repr(number)
        return out

    def to_json(self) -> str:
        """:meth:`record` as one line of JSON (the String output ``refusal``)."""
        return json.dumps(self.record(), allow_nan=False)

    @classmethod
    def from_record(cls, record: dict) -> RunError:
        """The error of a :meth:`record` (or of a JSON object read back); unknown keys are
        ignored, missing ones are None."""
        known = {f.name for f in fields(cls)}
        values = {k: v for k, v in record.items() if k in known}
        values["kind"] = RunStatus(values.get("kind", RunStatus.REFUSED))
        for name in _NUMBERS:
            if isinstance(values.get(name), str):
                values[name] = float(values[name])
        return cls(**{"message": "", **values})

    @classmethod
    def from_json(cls, text: str) -> RunError | None:
        """The error of :meth:`to_json`'s text; None for "" (no refusal)."""
        return cls.from_record(json.loads(text)) if text else None


#: The record's float fields (non-finite ones are written as strings).
_NUMBERS = ("time", "value")


def refusal_of(exc: BaseException, kind: RunStatus, message: str, instance: str, time: float) -> RunError:
    """The :class:`RunError` of a slave's refusal: ``exc``'s record when it is a model's
    (:class:`kernels.Refused`) or an inner component's (``exc.run_error``, in a system FMU:
    its instance becomes ``<instance>.<inner>``, an interruption stays one), its ``instance``
    and ``time`` filled in when unknown; the bare outcome otherwise.  ``message`` is the slave's message."""
    inner = getattr(exc, "run_error", None)
    if isinstance(inner, RunError):
        return replace(inner, kind=inner.kind if inner.kind is RunStatus.INTERRUPTED else kind, message=message,
                       instance=f"{instance}.{inner.instance}" if inner.instance else instance,
                       time=time if inner.time is None else inner.time)
    record = exc.record() if callable(getattr(exc, "record", None)) else {}
    return RunError.from_record({**record, "kind": kind, "message": message,
                                 "instance": record.get("instance") or instance,
                                 "time": time if record.get("time") is None else record["time"]})
