"""``pendulum_metrics``' windows and band hit exactly at their edges (issue 31: boundaries never
hit): a pitch of exactly :data:`BALANCED_DEG` is within the band, the sample exactly one second
before the last is outside the last second, and a pendulum last outside the band on the
second-to-last sample settles on the last one.  Synthetic columns at 2 ms whose times and angles
are exact (np.degrees(np.radians(0.1)) == 0.1; t = k × 0.002 gives t[2000] = 4.0 = t[-1] - 1)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from scenarios.scenes.pendulum import BALANCED_DEG, pendulum_metrics

H = 0.002
N = 2501        # 0 to 5 s


def _columns(psi_deg):
    t = np.arange(N) * H
    zero = np.zeros(N)
    return {"t": t, "psi": np.radians(np.asarray(psi_deg, dtype=float)), "phi": zero, "x": zero, "y": zero,
            "x_d": zero, "y_d": zero, "v_l": zero, "i_l": zero, "v_r": zero, "i_r": zero}


def test_a_pitch_of_exactly_the_band_is_within_it():
    """0.3 deg up to sample 999, then exactly 0.1 deg: settled at sample 1000's time (2.0 s).
    Catches ``>`` turned into ``>=`` (the run would never settle)."""
    psi = np.full(N, BALANCED_DEG)
    psi[:1000] = 0.3
    assert np.degrees(np.radians(BALANCED_DEG)) == BALANCED_DEG     # the edge is exact
    m = pendulum_metrics(_columns(psi), H)
    assert m["settling_time_s"] == 1000 * H == 2.0


def test_the_sample_exactly_one_second_before_the_last_is_not_in_the_last_second():
    """The last second is (t_end - 1, t_end]: a 0.09 deg spike at t = 4.0 s (t_end = 5.0 s) is not
    its peak, one at the next sample is.  Catches the window's 1e-9 taken the other way, the
    one second changed, and the peak taken over the whole run."""
    psi = np.full(N, 0.01)
    psi[0] = 0.05
    psi[2000] = 0.09
    assert np.arange(N)[2000] * H == 4.0
    m = pendulum_metrics(_columns(psi), H)
    assert m["last_second_pitch_deg"] == pytest.approx(0.01, rel=1e-12)
    assert m["peak_pitch_deg"] == pytest.approx(0.09, rel=1e-12)
    psi[2001] = 0.08
    assert pendulum_metrics(_columns(psi), H)["last_second_pitch_deg"] == pytest.approx(0.08, rel=1e-12)


def test_last_outside_on_the_second_to_last_sample_settles_on_the_last():
    """Outside until sample N-2, inside on sample N-1: settled at t[N-1] = 5.0 s, not NaN;
    outside on the last sample too: NaN.  Catches the bound on the next sample's index moved
    by one."""
    psi = np.full(N, 0.5)
    psi[-1] = 0.0
    assert pendulum_metrics(_columns(psi), H)["settling_time_s"] == pytest.approx(5.0, abs=1e-12)
    assert math.isnan(pendulum_metrics(_columns(np.full(N, 0.5)), H)["settling_time_s"])


def test_the_energy_is_the_step_times_the_sum_of_both_sides_power():
    """v_l i_l + v_r i_r summed and multiplied by the step (here 5 ms, not the scenes' 2 ms):
    constant 2 V × 0.5 A and -1 V × 0.25 A over 11 samples gives 0.005 × 11 × 0.75 J.
    Catches the step ignored, a side dropped, and a sign flipped."""
    n = 11
    c = {"t": np.arange(n) * 0.005, "psi": np.zeros(n), "phi": np.zeros(n), "x": np.zeros(n), "y": np.zeros(n),
         "x_d": np.zeros(n), "y_d": np.zeros(n), "v_l": np.full(n, 2.0), "i_l": np.full(n, 0.5),
         "v_r": np.full(n, -1.0), "i_r": np.full(n, 0.25)}
    assert pendulum_metrics(c, 0.005)["energy_J"] == pytest.approx(0.005 * n * (1.0 - 0.25), rel=1e-12)
