"""The compiled loop's schedule (kernels/src/loop.c ``pc_loop_run``) against a Python reference
written from its contract (kernels/src/loop.h): for plans of one or several groups, every group
one sub-step, every group several, and mixed, each member's calls (start time, length, the
inputs it read) in order, the values, every recorded row and the stop, from a step count k0 > 0
and a start time t0 != 0, with and without a member declining."""
from __future__ import annotations

import ctypes

import numpy as np
import pytest

from fmus.cosim.compiled import LoopPlan, Member
from kernels import Refusal

IO = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                      ctypes.POINTER(Refusal))
K0, K1, T0, H = 3, 8, 0.25, 0.1
#: Group layouts: (sub-steps, members) per group.
LAYOUTS = [((1, 2),), ((3, 2),), ((1, 1), (1, 2)), ((2, 1), (3, 2)), ((1, 1), (2, 1), (1, 2)), ((4, 1), (1, 1))]


def _output(m: int, a: float, b: float, t: float, dt: float) -> float:
    """Member m's output from its inputs (a, b) over [t, t + dt]: each term tells a wrong
    input, time or length apart."""
    return 0.5 * a - 0.25 * b + (m + 1) * t + 7.0 * dt + 0.125 * m


def _plan(layout, log, refuse=None):
    """Members 0 .. n-1 in the layout's groups; member m reads slot m (its predecessor's output;
    slot 0 a constant) and slot n (the last member's output), writes slot m + 1.  ``refuse``:
    (member, call number) that declines."""
    n = sum(count for _, count in layout)
    groups, m = [], 0
    for substeps, count in layout:
        members = []
        for _ in range(count):
            x = np.zeros(3)

            def step(_c, _x, t, dt, refusal, m=m, x=x):
                log.append((m, t, dt, x[0], x[1]))
                if refuse is not None and (m, sum(1 for e in log if e[0] == m)) == refuse:
                    refusal[0].code, refusal[0].index, refusal[0].value = 9, m, t
                    return 9
                x[2] = _output(m, x[0], x[1], t, dt)
                return 0

            callback = IO(step)
            member = Member(ctypes.cast(callback, ctypes.c_void_p).value, 0, x, [(0, m), (1, n)], [(2, m + 1)])
            member.callback = callback
            members.append(member)
            m += 1
        groups.append((substeps, members))
    return LoopPlan(groups, record_slots=list(range(n, -1, -1))), n


def _reference(layout, values, record, refuse=None):
    """loop.h's schedule in Python: step k from T0 + k H, group by group, sub-step j of a
    group of s from there + j (H / s), each member's inputs copied in, its step, its outputs
    copied out; row k + 1 the recorded slots after step k.  Returns the calls and the stop
    (step, member, sub-step, time)."""
    n = sum(count for _, count in layout)
    log, calls = [], {}
    for k in range(K0, K1):
        t = T0 + k * H
        m0 = 0
        for substeps, count in layout:
            dt = H / substeps
            for j in range(substeps):
                start = t + j * dt
                for m in range(m0, m0 + count):
                    a, b = values[m], values[n]
                    log.append((m, start, dt, a, b))
                    calls[m] = calls.get(m, 0) + 1
                    if refuse == (m, calls[m]):
                        return log, (k, m, j, t)
                    values[m + 1] = _output(m, a, b, start, dt)
            m0 += count
        record[k + 1] = values[list(range(n, -1, -1))]
    return log, (K1, -1, 0, T0 + K1 * H)


def _run(layout, refuse=None):
    log = []
    plan, n = _plan(layout, log, refuse)
    start = np.linspace(0.3, -0.2, n + 1)
    values, record = start.copy(), np.full((K1 + 1, n + 1), np.nan)
    stop = plan.run(values, record, K0, K1, T0, H)
    want_values, want_record = start.copy(), np.full((K1 + 1, n + 1), np.nan)
    want_log, want_stop = _reference(layout, want_values, want_record, refuse)
    assert log == want_log
    assert (stop.step, stop.member, stop.substep, stop.time) == want_stop
    assert values.tobytes() == want_values.tobytes()
    assert record.tobytes() == want_record.tobytes()
    return stop, log


@pytest.mark.parametrize("layout", LAYOUTS)
def test_every_layouts_calls_values_and_rows_are_the_contracts(layout):
    """Catches a loop that takes the one-run path (every member over the whole step) for a
    plan whose groups all have sub-steps, sub-steps of the wrong start or length, a member
    reading its inputs before its predecessor's output is copied (Gauss-Seidel order), rows
    recorded at the wrong index or from k = 0, or the stop's time not t0 + k1 h."""
    _run(layout)


@pytest.mark.parametrize("first", [True, False])
@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_member_declining_stops_at_its_step_sub_step_and_start_time(layout, first):
    """The first or the last member declines its fourth call: the stop names its step, member,
    sub-step and the step's start time, with its refusal, and nothing after it is stepped or
    recorded.  Catches the stop filled wrongly on either path, member 0's refusal taken for
    none, or the loop going on."""
    n = sum(count for _, count in layout)
    who = 0 if first else n - 1
    stop, log = _run(layout, refuse=(who, 4))
    assert stop.member == who and stop.step < K1 - 1
    assert (stop.refusal.code, stop.refusal.index, stop.refusal.value) == (9, who, log[-1][1])
