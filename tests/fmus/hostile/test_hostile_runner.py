"""fmus/hostile/worker.py's Runner, the judge of the hostile campaign, against made-up FMUs whose
behaviour the test sets: one that accepts every call must be found out on exactly the calls it
should have refused (a step size <= 0, a communication point that does not follow the last one,
a step after fmi2Terminate, a bad start time, a call out of order), and on none of the calls it
may accept (consecutive steps, a state set back); one that refuses must leave its message and
its record, with the record's status.  The campaign's own runs drive real FMUs in worker
processes and are of the slow kind (issue 31: seed 3501's survivor [22], the expected point
``t + last`` taken as ``t - last``, which only those runs reached)."""
from __future__ import annotations

import math
from types import SimpleNamespace

import pytest
from fmpy.fmi1 import FMICallException

from fmus.hostile import worker
from fmus.status import FmiStatus, RunError, RunStatus

#: The made-up FMU's variables: a Real output, the String outputs every parcosim FMU has.
VARIABLES = [SimpleNamespace(name="x", causality="output", type="Real", valueReference=0),
             SimpleNamespace(name="k", causality="parameter", type="Real", valueReference=1),
             SimpleNamespace(name="error", causality="output", type="String", valueReference=2),
             SimpleNamespace(name="refusal", causality="output", type="String", valueReference=3)]


class MadeUpFMU:
    """Stands for fmpy's FMU2Slave: records each doStep's (point, size) and accepts every call,
    except a doStep at a point in ``refuse_at``, refused with ``status`` leaving ``error`` and
    ``refusal`` as given."""

    refuse_at: tuple = ()
    status = FmiStatus.DISCARD
    error = ""
    refusal = ""
    x = 1.5

    def __init__(self, **kwargs):
        self.steps, self.states = [], 0

    def doStep(self, point, h):
        if point in self.refuse_at:
            raise FMICallException("doStep", int(self.status))
        self.steps.append((point, h))

    def getReal(self, refs):
        return [self.x for _ in refs]

    def getString(self, refs):
        return [{2: self.error, 3: self.refusal}[r].encode() for r in refs]

    def getFMUState(self):
        self.states += 1
        return f"state{self.states}"

    def __getattr__(self, name):      # instantiate, setupExperiment, setReal, terminate ...: accepted
        return lambda *args, **kwargs: None


def _run(monkeypatch, ops, start_time=0.25, fmu=MadeUpFMU, parameters=()):
    monkeypatch.setattr(worker, "FMU2Slave", fmu)
    md = SimpleNamespace(guid="{g}", coSimulation=SimpleNamespace(modelIdentifier="M"), modelVariables=VARIABLES)
    case = {"model": "M", "instance_name": "inst", "logging": False, "start_time": start_time,
            "ops": ops, "parameters": list(parameters)}
    runner = worker.Runner(case, "unused", md)
    runner.run()
    return runner


def test_consecutive_steps_and_a_state_set_back_are_no_problem(monkeypatch):
    """Steps of 1, 1 and 2 ms from 0.25 s, a state taken after the first and set back after
    the third, then a step from the state's time: the runner asks for the points that follow
    (t + last) and finds nothing wrong.  Catches the expected point taken as t - last (3501's
    [22]) or as t, the point asked for not following the last step, and the time of a state set
    back lost."""
    runner = _run(monkeypatch, [["step", None, 1e-3], ["get_state"], ["step", None, 1e-3],
                                ["step", None, 2e-3], ["set_state"], ["step", None, 1e-3], ["get"]],
                  parameters=[["k", 3.0]])
    assert runner.problems == [] and runner.refused is False
    assert runner.fmu.steps == [(0.25, 1e-3), (0.25 + 1e-3, 1e-3), (0.25 + 1e-3 + 1e-3, 2e-3), (0.25 + 1e-3, 1e-3)]
    assert all(status == "OK" for _, status in runner.statuses)
    labels = [label for label, _ in runner.statuses]
    assert labels[:5] == ["instantiate", "setupExperiment", "enterInitializationMode", "set k", "exitInitializationMode"]
    assert labels[-3:] == ["freeFMUstate", "terminate", "freeInstance"]


@pytest.mark.parametrize("op, problem", [
    (["step", 0.3, 1e-3], "doStep(0.3, 0.001) accepted a communication point that does not follow the last one "
                          "(0.251)"),
    (["step", None, 0.0], "doStep(0.251, 0.0) accepted a step size that is not finite and > 0"),
    (["step", None, -1e-3], "doStep(0.251, -0.001) accepted a step size that is not finite and > 0"),
    (["step", None, math.inf], "doStep(0.251, inf) accepted a step size that is not finite and > 0"),
    (["exit_init_again"], "exitInitializationMode in Step Mode returned OK, not fmi2Error"),
    (["setup_again"], "setupExperiment in Step Mode returned OK, not fmi2Error"),
])
def test_an_fmu_that_accepts_everything_is_found_out_on_each_call_it_should_refuse(monkeypatch, op, problem):
    """After a good 1 ms step from 0.25 s, one bad call: exactly its problem, worded as the
    campaign reports it.  Catches a check inverted, dropped or reporting another call."""
    runner = _run(monkeypatch, [["step", None, 1e-3], op])
    assert runner.problems == [problem]


def test_a_step_after_terminate_and_an_unusable_start_time_are_found_out(monkeypatch):
    """Catches ``terminated`` not followed, and a start time where 1 us does not count (or not
    finite) accepted without a problem."""
    runner = _run(monkeypatch, [["step", None, 1e-3], ["terminate"], ["step", None, 1e-3]])
    assert runner.problems == ["doStep(0.251, 0.001) after fmi2Terminate returned fmi2OK"]
    assert [label for label, _ in runner.statuses].count("terminate") == 1
    for start in (1e12, math.inf):
        runner = _run(monkeypatch, [], start_time=start)
        assert runner.problems == [f"setupExperiment({start!r}) returned OK, not fmi2Error"]


def test_non_finite_outputs_after_an_accepted_step_are_found_out(monkeypatch):
    """Catches the outputs not read after an fmi2OK step, or read and not checked."""
    fmu = type("NaNFMU", (MadeUpFMU,), {"x": math.nan})
    runner = _run(monkeypatch, [["step", None, 1e-3]], fmu=fmu)
    assert runner.problems == ["non-finite outputs after the fmi2OK doStep(0.25, 0.001): {'x': nan}"]


def _refusing(error, refusal, status=FmiStatus.DISCARD):
    return type("RefusingFMU", (MadeUpFMU,), {"refuse_at": (0.25 + 1e-3,), "error": error, "refusal": refusal,
                                             "status": status})


def test_a_refused_step_must_leave_its_message_and_its_record_with_the_records_status(monkeypatch):
    """The second step refused: with a message naming a variable and its record, nothing is
    wrong and the case is a refusal; an empty message, a record of another message or of
    another instance, no record, and a status other than the record's kind's are each one
    problem.  Catches each of these checks dropped or inverted."""
    message = "input x = nan at t = 0.251 s is not finite"
    good = RunError(RunStatus.REFUSED, message, instance="inst", time=0.251).to_json()
    ops = [["step", None, 1e-3], ["step", None, 1e-3]]
    runner = _run(monkeypatch, ops, fmu=_refusing(message, good))
    label = "doStep(0.251, 0.001)"
    assert runner.problems == [] and runner.refused is True and runner.statuses[6] == [label, "Discard"]

    assert _run(monkeypatch, ops, fmu=_refusing("", good)).problems[0] == \
        f"the refused {label} left error = '', naming nothing"
    other = RunError(RunStatus.REFUSED, message, instance="another", time=0.251).to_json()
    for refusal in (other, RunError(RunStatus.REFUSED, "another message", instance="inst").to_json()):
        assert _run(monkeypatch, ops, fmu=_refusing(message, refusal)).problems == [
            f"the refused {label} left refusal = {refusal.encode()!r}, not the record of error = {message!r}"]
    problems = _run(monkeypatch, ops, fmu=_refusing(message, "")).problems
    assert problems == [f"the refused {label} left refusal = b'', not the record of error = {message!r}"]
    assert _run(monkeypatch, ops, fmu=_refusing(message, good, FmiStatus.ERROR)).problems == [
        f"the refused {label} returned Error, not the Discard of a refused refusal"]


class RecordingFMU(MadeUpFMU):
    """A :class:`MadeUpFMU` that records every other call it receives, by name, with its
    arguments, in order."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.calls = []

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return lambda *args, **kwargs: self.calls.append((name, args, kwargs))


def test_every_op_of_a_case_is_the_fmi_call_it_names_with_its_own_arguments(monkeypatch):
    """A case of each op that sets a value (a variable by name, a value reference of each FMI
    type), a step before initialisation, a parameter, a call out of order and terminate: the
    FMU receives exactly those calls, in order, each with the op's own reference and value
    converted to the type's Python type, each recorded under its label.  Catches an op's
    field read from another position, a setter of another type, a value not converted, a
    parameter or an op dropped, and a label naming another call."""
    ops = [["step_before_init", 0.0, 2e-3], ["set", "k", 2.5], ["set_vr", "Integer", 7, 3.0],
           ["set_vr", "Boolean", 8, 0], ["set_vr", "String", 9, 12], ["set_vr", "Real", 0, "1.25"],
           ["step", None, 1e-3], ["enter_init_again"], ["terminate"]]
    runner = _run(monkeypatch, ops, start_time=0.5, fmu=RecordingFMU, parameters=[["k", 3.0]])
    calls = runner.fmu.calls
    assert calls == [("instantiate", (), {"loggingOn": False}), ("setupExperiment", (), {"startTime": 0.5}),
                     ("enterInitializationMode", (), {}), ("setReal", ([1], [3.0]), {}),
                     ("exitInitializationMode", (), {}), ("setReal", ([1], [2.5]), {}),
                     ("setInteger", ([7], [3]), {}), ("setBoolean", ([8], [False]), {}),
                     ("setString", ([9], ["12"]), {}), ("setReal", ([0], [1.25]), {}),
                     ("enterInitializationMode", (), {}), ("terminate", (), {}), ("freeInstance", (), {})]
    assert [type(args[1][0]) for name, args, _ in calls if name.startswith("set") and args] == \
        [float, float, int, bool, str, float]
    assert runner.fmu.steps == [(0.0, 2e-3), (0.5, 1e-3)]
    assert [label for label, _ in runner.statuses] == [
        "instantiate", "setupExperiment", "enterInitializationMode", "doStep before initialisation", "set k",
        "exitInitializationMode", "set k", "set_vr Integer 7", "set_vr Boolean 8", "set_vr String 9",
        "set_vr Real 0", "doStep(0.5, 0.001)", "get outputs", "out of order: enterInitializationMode",
        "terminate", "freeInstance"]
    assert runner.problems == ["doStep before initialisation returned fmi2OK",
                               "enterInitializationMode in Step Mode returned OK, not fmi2Error"]


class GuidCheckingFMU(MadeUpFMU):
    """A made-up FMU that, as fmi2Instantiate must, refuses (fmpy raises) a GUID that is not
    its model description's ``{g}``; it records the GUID it was given."""

    given = []

    def __init__(self, guid=None, **kwargs):
        super().__init__(**kwargs)
        self.guid = guid
        GuidCheckingFMU.given.append(guid)

    def instantiate(self, **kwargs):
        if self.guid != "{g}":
            raise Exception("Failed to instantiate model")      # fmpy's words for a NULL instance


@pytest.mark.parametrize("guid", [None, "own", "wrong"])
def test_a_case_instantiates_with_the_fmus_own_guid_unless_it_asks_for_another(monkeypatch, guid):
    """A case without a "guid" (the cases of before the lifecycle kind) or with "own" gets the
    model description's GUID and runs; "wrong" gets one that is not the FMU's, whose refusal is
    the expected answer.  Catches the default read from the wrong key (seed 4001's survivor
    [137], ``case.get("own", "guid")``: every case then instantiated with a foreign GUID)."""
    monkeypatch.setattr(worker, "FMU2Slave", GuidCheckingFMU)
    monkeypatch.setattr(GuidCheckingFMU, "given", [])
    md = SimpleNamespace(guid="{g}", coSimulation=SimpleNamespace(modelIdentifier="M"), modelVariables=VARIABLES)
    case = {"model": "M", "instance_name": "inst", "logging": False, "start_time": 0.25, "ops": [["step", None, 1e-3]],
            "parameters": []}
    if guid is not None:
        case["guid"] = guid
    runner = worker.Runner(case, "unused", md)
    runner.run()
    assert runner.problems == []
    if guid == "wrong":
        assert GuidCheckingFMU.given != ["{g}"] and len(GuidCheckingFMU.given) == 1
        assert runner.refused and runner.statuses == [["instantiate (another GUID)", "Error"]]
    else:
        assert GuidCheckingFMU.given == ["{g}"] and not runner.refused
        assert runner.statuses[0][0] == "instantiate" and runner.fmu.steps == [(0.25, 1e-3)]


def test_a_refusal_message_names_something_by_a_variable_an_assignment_or_a_time(monkeypatch):
    """A refused step's message that names none of the FMU's variables is enough when it
    assigns a value (" = ") or names the time ("t = "); one that does neither names nothing.
    Catches the assignment's test inverted (seed 4001's survivor [269]: every tested message
    named a variable, so the other two ways were never tried)."""
    ops = [["step", None, 1e-3], ["step", None, 1e-3]]
    label = "doStep(0.251, 0.001)"
    for message, named in (("speed = 3 rad/s is too high", True), ("it failed badly", False),
                           ("refused at t = 0.251 s", True)):
        assert not any(name in message for name in ("x", "k", "error", "refusal")), message
        record = RunError(RunStatus.REFUSED, message, instance="inst", time=0.251).to_json()
        problems = _run(monkeypatch, ops, fmu=_refusing(message, record)).problems
        assert problems == ([] if named else [f"the refused {label} left error = {message!r}, naming nothing"]), message


def test_the_judge_and_the_fmus_own_rule_split_the_start_times_at_the_same_double(monkeypatch):
    """Seed 4101's survivor [209] (worker.py:168, the time resolution 1e-6 -> 2e-6 passed: no
    start time between the two edges was tried).  A start time is unusable when t0 + 1 us ==
    t0 (docs/extremes.md; :data:`fmus.slave.base.TIME_RESOLUTION`): below 2**34 s a double's
    half ulp is at most 2**-20 s < 1 us, so 1 us still counts; from 2**34 s the half ulp is
    2**-19 s > 1 us and it is lost.  The judge must find fault with an FMU that accepts 2**34
    and with none that accepts the double under it, the same split as the FMUs' own check."""
    from fmus.slave.base import FmiError, check_experiment_times

    edge = 2.0 ** 34
    below = math.nextafter(edge, 0.0)
    check_experiment_times(below)
    with pytest.raises(FmiError):
        check_experiment_times(edge)
    assert _run(monkeypatch, [], start_time=below).problems == []
    assert _run(monkeypatch, [], start_time=edge).problems == [f"setupExperiment({edge!r}) returned OK, not fmi2Error"]
