"""The words and records of a slave's refusals (fmus/slave/base.py ``do_step``, ``_refuse``), on a
made-up slave whose initialisation and steps refuse when the test says: the refused step's
message with its time, the later steps' message naming the first refusal and the way out, the
initialisation's refusal said again at each step, an interruption, a step after fmi2Terminate or
before initialisation, each in ``error``, in the log and as the record in ``refusal`` (kind,
instance, time, message) (issue 31: error paths' messages naming what, the value and the time;
docs/extremes.md's table of the FMI calls under hostile use).  In process: fast."""
from __future__ import annotations

import pytest

from fmus.slave.base import GuardedSlave
from fmus.status import RunError, RunStatus


class Plan(GuardedSlave):
    """``k`` < 0 refuses the initialisation, ``k`` = 99 interrupts it; a step from ``fail_at``
    refuses, one from ``stop_at`` is interrupted."""

    fail_at = stop_at = 1e9

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.declare("k", "parameter", 1.0, "a parameter")
        self.declare("x", "output", 0.0, "steps taken")

    def setup(self):
        if self.k == 99.0:
            raise KeyboardInterrupt
        if self.k < 0.0:
            raise ValueError(f"parameter k = {self.k!r} must be >= 0")
        self.x = 0.0

    def step(self, current_time, step_size):
        if current_time >= self.stop_at:
            raise KeyboardInterrupt
        if current_time >= self.fail_at:
            raise ValueError("x would be nan")
        self.x += 1.0


def _plan(k=1.0, initialise=True, **attributes) -> Plan:
    slave = Plan(instance_name="inst")
    vars(slave).update(attributes)
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave.set_real([next(vr for vr, v in slave.vars.items() if v.name == "k")], [k])
    if initialise:
        slave.exit_initialization_mode()
    return slave


def _record(slave) -> tuple:
    r = RunError.from_json(slave.refusal)
    return r.kind, r.instance, r.time, r.message


def test_a_refused_step_says_why_and_when_and_later_steps_name_it_until_a_state_is_restored():
    """Catches the step's time left out of its message, the record of another kind or time, a
    later step taken or refused without naming the first refusal, and a state set back not
    clearing it."""
    slave = _plan(fail_at=2e-3)
    assert slave.do_step(0.0, 1e-3) and slave.do_step(1e-3, 1e-3)
    before = slave._get_fmu_state()            # fmi2GetFMUstate (pythonfmu's call)
    assert not slave.do_step(2e-3, 1e-3)
    assert slave.error == "x would be nan (step from t = 0.002 s)" and slave.refused_because == "x would be nan"
    assert _record(slave) == (RunStatus.REFUSED, "inst", 2e-3, "x would be nan (step from t = 0.002 s)")
    assert slave.log_queue[-1].msg == "inst: x would be nan (step from t = 0.002 s)"
    assert not slave.do_step(2e-3, 1e-3)
    assert slave.error == "x would be nan (step from t = 0.002 s)"            # kept, with its record
    assert _record(slave)[0] is RunStatus.REFUSED and slave.x == 2.0
    assert slave.log_queue[-1].msg == ("inst: an earlier step was refused (x would be nan (step from t = 0.002 s)); "
                                       "restore an FMU state taken before it (fmi2SetFMUstate) to go on; step from "
                                       "t = 0.002 s refused")
    slave._set_fmu_state(before)
    slave.fail_at = 1e9
    assert slave.do_step(2e-3, 1e-3), slave.error
    assert (slave.error, slave.refusal, slave.x) == ("", "", 3.0)


def test_a_refused_initialisation_is_said_again_at_each_step_with_its_record():
    slave = _plan(k=-1.0)
    message = "initialisation refused: parameter k = -1.0 must be >= 0 (t = 0 s)"
    assert slave.error == message and slave.refused_because == "parameter k = -1.0 must be >= 0"
    assert _record(slave) == (RunStatus.INITIALISATION, "inst", 0.0, message)
    assert not slave.do_step(0.0, 1e-3)
    assert slave.error == message and _record(slave)[0] is RunStatus.INITIALISATION
    assert slave.log_queue[-1].msg == f"inst: {message}; step from t = 0 s refused"


@pytest.mark.parametrize("where", ["initialisation", "step"])
def test_an_interruption_is_a_record_of_its_own_kind(where):
    """Catches a KeyboardInterrupt escaping, recorded as a refusal of the model, or leaving the
    slave ready to step on (the next step must be refused naming it)."""
    if where == "initialisation":
        slave = _plan(k=99.0)
        message, time = "initialisation refused: interrupted (KeyboardInterrupt) (t = 0 s)", 0.0
    else:
        slave = _plan(stop_at=1e-3)
        assert slave.do_step(0.0, 1e-3)
        assert not slave.do_step(1e-3, 1e-3)
        message, time = "step interrupted (KeyboardInterrupt) at t = 0.001 s", 1e-3
    assert slave.error == message and slave.refused_because == "interrupted (KeyboardInterrupt)"
    assert _record(slave) == (RunStatus.INTERRUPTED, "inst", time, message)
    x = slave.x
    slave.stop_at = 1e9
    assert not slave.do_step(time, 1e-3)
    assert slave.x == x and slave.error == message
    again = (f"an earlier step was refused ({message}); restore an FMU state taken before it (fmi2SetFMUstate) "
             f"to go on" if where == "step" else message)
    assert slave.log_queue[-1].msg == f"inst: {again}; step from t = {time:.6g} s refused"


def test_a_step_after_terminate_or_before_initialisation_is_refused_naming_the_call():
    slave = _plan()
    assert slave.do_step(0.0, 1e-3)
    slave.terminate()
    assert not slave.do_step(1e-3, 1e-3)
    assert slave.error == "doStep from t = 0.001 s after fmi2Terminate refused"
    assert _record(slave) == (RunStatus.REFUSED, "inst", 1e-3, slave.error)
    early = _plan(initialise=False)
    assert not early.do_step(0.0, 1e-3)
    assert early.error == "doStep from t = 0.0 s before initialisation (fmi2ExitInitializationMode) refused"
    assert _record(early) == (RunStatus.REFUSED, "inst", 0.0, early.error)
