"""The errors of the in-process back end (fmus/cosim/backends.py ``InProcessInstance``): each
call that fails names the instance, the time of that call and the slave's message, whether
the slave raised (as an FMU's fatal error) or refused (``do_step`` returned False, with its
record).  Held at start and step times that differ from each other and from the step size,
so that a time taken from the wrong argument shows.
"""
from __future__ import annotations

import pytest

from fmus.cosim.backends import CoSimulationError, InProcessInstance
from fmus.status import RunStatus

T0, H = 0.25, 1e-3


def _instance(name: str = "traj") -> InProcessInstance:
    inst = InProcessInstance("Trajectory", name)
    inst.initialize({}, T0)
    return inst


def test_a_step_the_slave_raises_in_names_the_instance_the_steps_time_and_the_message(monkeypatch):
    """Catches the time of the failing step replaced by its size or the start time, the
    instance or message lost."""
    inst = _instance()
    t = T0 + 7 * H
    monkeypatch.setattr(inst.slave, "do_step", lambda current_time, step_size: 1 / 0)
    with pytest.raises(CoSimulationError) as caught:
        inst.do_step(t, H)
    assert (caught.value.instance, caught.value.time, caught.value.message) == ("traj", t, "division by zero")
    assert str(caught.value) == f"traj refused the step from t = {t:.6g} s: division by zero"


def test_a_refused_step_names_its_time_and_carries_the_slaves_record():
    """A step at a time that does not follow the last one is refused by the slave (False):
    the error's time is that step's, its message and record the slave's."""
    inst = _instance("other")
    inst.do_step(T0, H)
    t = T0 + 5 * H                      # the next step starts at T0 + H
    with pytest.raises(CoSimulationError) as caught:
        inst.do_step(t, H)
    err = caught.value
    assert (err.instance, err.time) == ("other", t)
    assert err.message == inst.slave.error and err.message
    assert err.run_error is not None and err.run_error.kind is not RunStatus.INTERRUPTED
    assert err.run_error.message == inst.slave.error


def test_initialisation_errors_name_the_start_time(monkeypatch):
    """Catches the start time of a failing set-up or exit of initialisation lost."""
    inst = InProcessInstance("Trajectory", "t0")
    monkeypatch.setattr(inst.slave, "setup_experiment", lambda *args: {}["tolerance"])
    with pytest.raises(CoSimulationError) as caught:
        inst.enter_initialization({}, T0)
    assert (caught.value.instance, caught.value.time, caught.value.message) == ("t0", T0, "'tolerance'")
    fresh = InProcessInstance("Trajectory", "t1")
    fresh.enter_initialization({}, 2 * T0)
    monkeypatch.setattr(fresh.slave, "exit_initialization_mode", lambda: [][1])
    with pytest.raises(CoSimulationError) as caught:
        fresh.exit_initialization()
    assert (caught.value.instance, caught.value.time, caught.value.message) == ("t1", 2 * T0,
                                                                                  "list index out of range")
