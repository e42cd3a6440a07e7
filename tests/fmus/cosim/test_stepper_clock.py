"""The master's one clock: step k starts at t_0 + k h, from the integer k, never a running sum
(fmus/cosim/stepper.py, kernels/src/loop.c; docs/master.md "The clock")."""
from __future__ import annotations

import numpy as np
import pytest

from controller.trajectories import from_parameters
from fmus.cosim.master import simulate
from fmus.cosim.stepper import Entry, Stepper, rate_groups
from fmus.cosim.system import Component, System

H = 1e-3
STEPS = 10_000        # t + h summed 10^4 times is off k h by up to 1e-12 s (about 1 s in)


class _Clock:
    """An instance that only notes the (t, h) of each doStep."""

    def __init__(self, name, calls):
        self.name, self.calls = name, calls

    def set_inputs(self, values):
        pass

    def do_step(self, t, h):
        self.calls.append((self.name, t, h))

    def get_outputs(self):
        return []


def _stepper(substeps: dict, calls: list) -> Stepper:
    """A stepper over clock-noting instances with ``substeps`` (name -> n), in that order."""
    stepper = Stepper.__new__(Stepper)
    stepper.system = System((), (), (), stop_time=STEPS * H, step=H)
    stepper.values, stepper.jacobi, stepper._calls = [], False, {}
    stepper.plan = tuple(Entry(n, _Clock(n, calls), (), (), (), (), s) for n, s in substeps.items())
    stepper.groups = tuple(rate_groups(stepper.plan))
    stepper._program = stepper._program_of(stepper.groups)
    stepper.at_step(0, 0.0)
    return stepper


def test_a_long_run_steps_every_instance_at_k_h_and_sub_steps_at_k_h_plus_j_h_over_n():
    """Catches a clock that sums t + h (off k h in the last bits after a few steps), sub-step
    times summed within a step, or a retried (split) step timed by anything but its index."""
    calls = []
    stepper = _stepper({"a": 1, "b": 4, "c": 4}, calls)
    for k in range(STEPS):
        if k % 997 == 5:
            stepper.step(split={"b": 3})            # a retried step: b alone in 12 sub-steps of h / 12
        else:
            stepper.step()
        assert stepper.k == k + 1 and stepper.time == (k + 1) * H
    expected = []
    for k in range(STEPS):
        t = k * H
        expected.append(("a", t, H))
        if k % 997 == 5:       # b split from its group: its 12 sub-steps, then c's 4
            expected += [("b", t + j * (H / 12), H / 12) for j in range(12)]
            expected += [("c", t + j * (H / 4), H / 4) for j in range(4)]
        else:
            for j in range(4):
                expected += [("b", t + j * (H / 4), H / 4), ("c", t + j * (H / 4), H / 4)]
    assert calls == expected
    summed = 0.0
    for _ in range(STEPS):
        summed += H
    assert summed != STEPS * H       # the test's premise: the sum leaves k h


def test_the_clock_survives_a_state_restore_and_a_start_time():
    """Catches a restored run that goes on from a time the state does not hold, or a start
    time added as a sum rather than t_0 + k h."""
    calls = []
    stepper = _stepper({"a": 1}, calls)
    stepper.at_step(0, 0.25)
    for _ in range(100):
        stepper.step()
    state = {"start_time": stepper.start_time, "step": stepper.k, "time": stepper.time}
    for _ in range(50):
        stepper.step()
    stepper.at_step(state["step"], state["start_time"])
    calls.clear()
    stepper.step()
    assert calls == [("a", 0.25 + 100 * H, H)] and stepper.time == 0.25 + 101 * H


@pytest.mark.parametrize("mode", ["inprocess", "compiled"])
@pytest.mark.parametrize("substeps", [1, 4])
def test_recorded_reference_is_the_trajectory_at_k_h_in_python_and_in_c(mode, substeps):
    """Catches the in-process stepper or the C loop (kernels/src/loop.c) timing step k by a
    running sum, or a multi-rate group's sub-steps summed: the Trajectory publishes its value at
    the end of its (sub-)step, t_k + (n-1) h/n + h/n, which then differs in the last bits."""
    parameters = {"kind": "circle", "cycles": 2}
    system = System((Component("traj", "Trajectory", parameters, substeps=substeps),), (),
                    ("traj.x_d", "traj.ddy_d"), stop_time=2.0, step=H)
    result = simulate(system, mode=mode)
    assert result.error is None and result.mode == mode
    trajectory = from_parameters(**parameters)
    k = np.arange(1, len(result.time))
    dt = H / substeps
    ends = [((i - 1) * H + (substeps - 1) * dt) + dt for i in k]
    samples = [trajectory(t) for t in ends]
    assert np.array_equal(result["traj.x_d"][1:], [s.x for s in samples])
    assert np.array_equal(result["traj.ddy_d"][1:], [s.ddy for s in samples])
    assert np.array_equal(result.time, np.arange(len(result.time)) * H)
