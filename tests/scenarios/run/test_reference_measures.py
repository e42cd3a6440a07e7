"""scenarios/reference.py's measures on runs made up here (the reference's own runs are of the
slow kind): a run at 2 ms against a reference at 1 ms (every second reference row), the
deviation over a window against its definition, the encoder differences, a system's parameters
changed (issue 31: a second sample time; values against an independent computation)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from scenarios.reference import common_rows, deviation, encoder_differences, with_parameters
from scenarios.scenes import get_scene


class _Run:
    def __init__(self, time, **signals):
        self.time, self.signals = np.asarray(time), {f"plant.{k}": np.asarray(v) for k, v in signals.items()}

    def __getitem__(self, signal):
        return self.signals[signal]


def _runs():
    """A run at 2 ms whose times carry a master's rounding, a reference at 1 ms over 0.1 s."""
    reference_t = np.arange(101) * 1e-3
    run_t = np.cumsum(np.full(51, 2e-3)) - 2e-3                      # t + h summed: off by ulps
    reference = _Run(reference_t, x=0.01 * np.sin(reference_t), y=0.1 + 0.0 * reference_t,
                     q1_enc=(np.arange(101) // 20) * 0.02, q2_enc=np.zeros(101))
    dx = 1e-6 * np.arange(51)
    dy = -2e-6 * np.cos(40 * run_t)
    q1 = (2 * np.arange(51) // 20) * 0.02                            # the same counts, per row
    q1[30] += 0.02                                                    # at 60 ms: one count off
    run = _Run(run_t, x=0.01 * np.sin(np.arange(51) * 2e-3) + dx, y=0.1 + dy, q1_enc=q1, q2_enc=np.zeros(51))
    return run, reference, dx, dy


def test_the_grids_meet_at_every_second_reference_row_to_a_nanosecond():
    """Catches the run-to-reference row matching done by exact time equality (the grids are ulps apart,
    nothing would match) or pairing the wrong rows."""
    run, reference, _, _ = _runs()
    assert not np.array_equal(run.time, reference.time[::2])          # ulps apart
    ia, ib = common_rows(run.time, reference.time)
    assert ia.tolist() == list(range(51)) and ib.tolist() == list(range(0, 101, 2))


def test_the_deviation_over_a_window_is_its_definition_over_the_common_rows():
    """[0.02, 0.08] s: rows 10..40 of the run; rms, max and where.  Catches the rows paired
    wrong, the window's ends, x or y left out, the time of the maximum of the other grid."""
    run, reference, dx, dy = _runs()
    got = deviation(run, reference, start=0.02, end=0.08)
    d = [math.hypot(dx[k], dy[k]) for k in range(10, 41)]
    assert got["rows"] == 31
    assert got["rms"] == pytest.approx(math.sqrt(sum(v * v for v in d) / len(d)), rel=1e-6)
    assert got["max"] == pytest.approx(max(d), rel=1e-6)
    assert got["t_max"] == pytest.approx(2e-3 * (10 + d.index(max(d))), abs=1e-12)
    assert deviation(run, reference)["rows"] == 51
    empty = deviation(run, reference, start=0.2)
    assert empty["rows"] == 0 and math.isnan(empty["rms"]) and math.isnan(empty["t_max"])


def test_encoder_differences_count_the_common_rows_that_differ_and_the_first_time():
    """Catches encoder differences counted over rows the runs do not share, or a first time given when
    nothing differs."""
    run, reference, _, _ = _runs()
    assert encoder_differences(run, reference) == (1, pytest.approx(0.06, abs=1e-12))
    assert encoder_differences(reference, reference) == (0, pytest.approx(math.nan, nan_ok=True))


def test_with_parameters_changes_one_instance_and_its_sub_steps_only():
    """Catches a reference variant that changes other instances too, keeps sub-steps it was told to change
    (or changes them when not told), or ignores an unknown instance."""
    system = get_scene("bench_circle_TCMDx").system
    changed = with_parameters(system, "drive2", component_substeps=4, R=1.5, T=2e-3)
    for before, after in zip(system.components, changed.components, strict=True):
        if before.name == "drive2":
            assert after.parameters == {**before.parameters, "R": 1.5, "T": 2e-3} and after.substeps == 4
        else:
            assert after == before
    assert with_parameters(system, "drive2", R=1.5).component("drive2").substeps == 1
    with pytest.raises(KeyError):
        with_parameters(system, "drive3", R=1.5)
