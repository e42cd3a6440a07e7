"""The hostile campaign's judge (fmus/hostile/worker.py ``Runner``) at its two numeric edges, hit
exactly (issue 31, session 44: a limit's constant and its comparison mattered in no test).

* docs/extremes.md "The campaign": a call over 10 s is a violation.  A made-up clock makes one
  doStep take exactly 10 s (no problem: "over") and 10.5 s (the problem, naming the call, its
  time and the limit).
* A communication point follows the last one to 1e-9 of max(|t|, 1 ms), the slaves' own rule
  (fmus/slave/base.py ``_check_communication_point``): an FMU that accepts a point 0.8 of that
  tolerance off is not found out, one 1.25 of it off is, on either side and at t below and above
  1 ms.
"""
from __future__ import annotations

import pytest

from fmus.hostile import worker
from tests.fmus.hostile.test_hostile_runner import MadeUpFMU, _run


class _Clock:
    """``perf_counter`` of the worker: moves only when the FMU's doStep says how long it took."""

    now = 0.0

    @classmethod
    def perf_counter(cls):
        return cls.now


def _slow_fmu(seconds: float):
    class SlowFMU(MadeUpFMU):
        def doStep(self, point, h):
            _Clock.now += seconds
            super().doStep(point, h)
    return SlowFMU


@pytest.mark.parametrize("seconds, problems", [
    (10.0, []),
    (10.5, ["doStep(0.25, 0.001) took 10.5 s (limit 10 s)"]),
])
def test_a_call_taking_over_ten_seconds_is_a_problem_and_one_of_ten_is_not(monkeypatch, seconds, problems):
    monkeypatch.setattr(worker, "time", _Clock)
    runner = _run(monkeypatch, [["step", None, 1e-3]], fmu=_slow_fmu(seconds))
    assert runner.problems == problems


@pytest.mark.parametrize("start", [0.25, -5e-4])
@pytest.mark.parametrize("side", [1, -1])
def test_a_point_within_the_slaves_tolerance_passes_the_judge_and_one_beyond_it_does_not(monkeypatch, start, side):
    """After one 1 ms step from ``start``, the next point asked for off the expected one by 0.8
    and 1.25 times 1e-9 max(|t|, 1 ms) (below 1 ms: the 1 ms floor)."""
    expected = start + 1e-3
    tolerance = 1e-9 * max(abs(expected), 1e-3)
    near = expected + side * 0.8 * tolerance
    assert _run(monkeypatch, [["step", None, 1e-3], ["step", near, 1e-3]], start_time=start).problems == []
    far = expected + side * 1.25 * tolerance
    assert _run(monkeypatch, [["step", None, 1e-3], ["step", far, 1e-3]], start_time=start).problems == [
        f"doStep({far!r}, 0.001) accepted a communication point that does not follow the last one ({expected!r})"]
