"""The compiled mode's C loop (kernels/src/loop.c) on members whose I/O steps are ctypes
callbacks: stepping order, sub-steps and their start times, the slot copies, the recorded
rows, and where a declining member stops it.  Runs under the sanitizers too
(tests/kernels/test_sanitizers.py), which checks the loop's indexing of the plan's arrays."""
from __future__ import annotations

import ctypes

import numpy as np

from fmus.cosim.compiled import LoopPlan, Member
from kernels import Refusal

IO = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                      ctypes.POINTER(Refusal))


def _member(step, x, inputs=(), outputs=()):
    callback = IO(step)
    member = Member(ctypes.cast(callback, ctypes.c_void_p).value, 0, x, inputs, outputs)
    member.callback = callback      # kept alive with the plan
    return member


def _plan(calls, refuse_at=None):
    clock_x = np.zeros(1)
    acc_x = np.zeros(2)        # input u, output: the running integral of u

    def clock(_c, _x, t, h):
        calls.append(("clock", t, h))
        clock_x[0] = t + h      # the time at the step's end
        return 0

    def integrate(_c, _x, t, h, refusal):
        calls.append(("acc", t, h))
        if refuse_at is not None and abs(t - refuse_at) < 1e-12:
            refusal[0].code, refusal[0].index, refusal[0].value = 7, 1, acc_x[0]
            return 7
        acc_x[1] += h * acc_x[0]
        return 0

    groups = [(1, [_member(lambda c, x, t, h, r: clock(c, x, t, h), clock_x, (), [(0, 0)])]),
              (2, [_member(integrate, acc_x, [(0, 0)], [(1, 1)])])]
    return LoopPlan(groups, record_slots=[1, 0]), acc_x


def test_members_step_in_order_with_their_sub_steps_and_the_rows_are_recorded():
    """Catches a C loop that steps members out of order, with wrong sub-steps, or loses rows."""
    calls = []
    plan, acc = _plan(calls)
    values, record = np.zeros(2), np.full((5, 2), np.nan)
    stop = plan.run(values, record, 0, 4, 0.0, 0.5)
    assert stop.step == 4 and stop.member == -1 and stop.time == 2.0
    assert calls[:3] == [("clock", 0.0, 0.5), ("acc", 0.0, 0.25), ("acc", 0.25, 0.25)]
    assert len(calls) == 12
    # u = t_end of each step (0.5, 1, 1.5, 2), held over both sub-steps: integral = sum 0.5 u
    expected = np.cumsum(0.5 * np.array([0.5, 1.0, 1.5, 2.0]))
    assert np.array_equal(record[1:, 0], expected) and np.array_equal(record[1:, 1], [0.5, 1.0, 1.5, 2.0])
    assert np.isnan(record[0]).all() and acc[1] == expected[-1]


def test_a_declining_member_stops_the_loop_where_it_declined_with_its_refusal():
    """Catches a C loop that goes on after a refusal or reports the wrong step or member."""
    calls = []
    plan, acc = _plan(calls, refuse_at=1.25)     # step 2 (t = 1), second sub-step
    values, record = np.zeros(2), np.full((5, 2), np.nan)
    stop = plan.run(values, record, 0, 4, 0.0, 0.5)
    assert (stop.step, stop.member, stop.substep, stop.time) == (2, 1, 1, 1.0)
    assert (stop.refusal.code, stop.refusal.index, stop.refusal.value) == (7, 1, 1.5)
    assert np.isnan(record[3:]).all() and not np.isnan(record[:3][1:]).any()
    assert values[1] == acc[1] == 0.5 * 0.5 + 0.5 * 1.0 + 0.25 * 1.5   # nothing after the refusal
