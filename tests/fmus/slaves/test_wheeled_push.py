"""WheeledPendulum's push parameters held to their description (issue 31; session 43's training
seed 4321 [19] in fmus/slaves/parcosim_wheeledpendulum.py): the push torque is *added* to the
disturbance input ``tau_d`` over the steps that start in [push_start, push_start +
push_duration), so a pushed run equals, to the last bit, an unpushed one fed that sum."""
from __future__ import annotations

import pytest

from fmus.slaves.parcosim_wheeledpendulum import OUTPUTS, WheeledPendulum

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
