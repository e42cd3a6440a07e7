"""scenarios/reference.py's ``deviation`` window at its edges, hit exactly (issue 31, session 44:
boundaries of the generalised training sample): rows at start <= t <= end count, with a slack
of 1e-12 s for a time's rounding, on either side -- inclusive."""
from __future__ import annotations

import numpy as np
import pytest

from scenarios.reference import deviation

START, END = 0.02, 0.08


class _Run:
    def __init__(self, time, x, y):
        self.time, self.signals = np.asarray(time), {"plant.x": np.asarray(x), "plant.y": np.asarray(y)}

    def __getitem__(self, signal):
        return self.signals[signal]


def _deviation(times, distances):
    """``deviation`` over [START, END] of a run off the reference by ``distances`` along x at ``times``."""
    reference = _Run(times, np.zeros(len(times)), np.full(len(times), 0.1))
    run = _Run(times, np.asarray(distances), np.full(len(times), 0.1))
    return deviation(run, reference, start=START, end=END)


def test_rows_exactly_the_slack_outside_the_window_are_in_it():
    """Rows at START - 1e-12 and END + 1e-12 (the slack's own ends) count: the largest distance
    is theirs and the rows are 3.  Catches a strict comparison at either end."""
    times = [0.0, START - 1e-12, 0.05, END + 1e-12, 0.09]
    got = _deviation(times, [9.0, 3.0, 1.0, 2.0, 8.0])
    assert got["rows"] == 3 and got["max"] == 3.0 and got["t_max"] == START - 1e-12
    assert got["rms"] == pytest.approx(((9.0 + 1.0 + 4.0) / 3) ** 0.5, rel=1e-15)
    got = _deviation(times, [9.0, 1.0, 1.0, 3.0, 8.0])
    assert got["rows"] == 3 and got["max"] == 3.0 and got["t_max"] == END + 1e-12


def test_rows_beyond_the_slack_are_not_in_the_window():
    """Rows 2e-12 s outside either end do not count (nor rows far outside).  Catches a wider
    slack or a window end dropped."""
    times = [0.0, START - 2e-12, 0.05, END + 2e-12, 0.09]
    got = _deviation(times, [9.0, 3.0, 1.0, 2.0, 8.0])
    assert got["rows"] == 1 and got["max"] == 1.0 and got["t_max"] == 0.05
