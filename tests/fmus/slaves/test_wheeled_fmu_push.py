"""WheeledPendulum's push and initial-state parameters held to their descriptions (issue 31; session 43's training
seed 4321 [19] in fmus/slaves/parcosim_wheeledpendulum.py): the push torque is *added* to the
disturbance input ``tau_d`` over the steps that start in [push_start, push_start +
push_duration), so a pushed run equals, to the last bit, an unpushed one fed that sum; each
initial-state parameter is its state entry's output at initialisation."""
from __future__ import annotations

import pytest

from fmus.slaves.parcosim_wheeledpendulum import INITIAL, OUTPUTS, WheeledPendulum

H = 1e-3


def _run(parameters: dict, tau_d) -> list:
    """A WheeledPendulum with ``parameters`` stepped 8 times by 1 ms from t = 0 with the input
    tau_d = ``tau_d(k)`` in step k; each step's outputs."""
    slave = WheeledPendulum(instance_name="pendulum")
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    for name, value in {"psi0": 0.02, **parameters}.items():
        slave.set_real([vr[name]], [value])
    slave.exit_initialization_mode()
    assert slave.error == ""
    rows = []
    for k in range(8):
        slave.set_real([vr["tau_d"]], [tau_d(k)])
        assert slave.do_step(k * H, H), slave.error
        rows.append([getattr(slave, name) for name, _ in OUTPUTS])
    return rows


@pytest.mark.parametrize("tau_d", [0.0, 0.01])
def test_a_push_is_its_torque_added_to_tau_d_over_the_steps_starting_in_its_window(tau_d):
    """A push of 0.05 N m from t = 2 ms for 3 ms acts in the steps from 2, 3 and 4 ms (its
    start included, its end excluded) and adds to the input: the same run unpushed with
    tau_d + 0.05 in those steps gives the same outputs to the last bit, and the push changes
    the run.  Catches the torque subtracted (training seed 4321 [19]), replacing tau_d, or the
    window's ends moved by a step."""
    push = {"push_torque": 0.05, "push_start": 2 * H, "push_duration": 3 * H}
    pushed = _run(push, lambda k: tau_d)
    fed = _run({}, lambda k: tau_d + 0.05 if 2 <= k < 5 else tau_d)
    assert pushed == fed
    assert pushed != _run({}, lambda k: tau_d)


def test_a_push_of_zero_duration_pushes_nothing():
    """push_duration = 0: the window [start, start) is empty."""
    assert _run({"push_torque": 0.05, "push_start": 2 * H, "push_duration": 0.0}, lambda k: 0.0) == \
        _run({}, lambda k: 0.0)


def test_a_negative_push_duration_is_refused_naming_it():
    """A push of -1 ms: initialisation refused with the parameter, its value and the rule."""
    slave = WheeledPendulum(instance_name="pendulum")
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    slave.set_real([vr["push_duration"]], [-1e-3])
    slave.exit_initialization_mode()
    assert slave.error == "initialisation refused: parameter push_duration = -0.001 s must be >= 0 (t = 0 s)"


def test_each_initial_state_parameter_is_its_outputs_value_at_initialisation():
    """theta0 ... y0 set to distinct values: each output theta ... y reads its own parameter's
    value at once.  Catches two entries of the table swapped or one left at its default."""
    slave = WheeledPendulum(instance_name="pendulum")
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    values = {name: 0.01 * (k + 1) for k, (name, _) in enumerate(INITIAL)}
    for name, value in values.items():
        slave.set_real([vr[name]], [value])
    slave.exit_initialization_mode()
    assert slave.error == ""
    assert {entry: getattr(slave, entry) for _, entry in INITIAL} == {entry: values[name] for name, entry in INITIAL}
    assert [entry for _, entry in INITIAL] == ["theta", "psi", "phi", "dtheta", "dpsi", "dphi", "x", "y"]


@pytest.mark.parametrize("start_off, end_off, first, last", [
    (0.5e-9, 0.0, 2, 5), (1.5e-9, 0.0, 3, 5),        # the start: within 1 ns of a step's start or not
    (0.0, 0.5e-9, 2, 5), (0.0, 1.5e-9, 2, 6),        # the end: within 1 ns of a step's start or not
])
def test_the_push_window_ends_are_rounded_by_one_nanosecond_and_no_more(start_off, end_off, first, last):
    """The window's ends are taken 1 ns early (the slave's comment: rounding of t), so a push
    starting 0.5 ns after a step's start acts from that step, 1.5 ns after from the next; an end
    0.5 ns after a step's start excludes that step, 1.5 ns includes it.  Catches the 1e-9 margin
    changed (doubled: 1.5 ns taken as rounding) or dropped from either end."""
    push = {"push_torque": 0.05, "push_start": 2 * H + start_off, "push_duration": 3 * H + end_off - start_off}
    fed = _run({}, lambda k: 0.05 if first <= k < last else 0.0)
    assert _run(push, lambda k: 0.0) == fed
