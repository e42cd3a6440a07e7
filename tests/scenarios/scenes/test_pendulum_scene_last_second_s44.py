"""``pendulum_metrics``' last second at its slack's edge (issue 31, session 44: boundaries of the
generalised training sample).  The last second is (t_end - 1, t_end], taken as
t >= t_end - 1 + 1e-9 (a nanosecond against a time's rounding): a sample exactly there is in it."""
from __future__ import annotations

import numpy as np
import pytest

from scenarios.scenes.pendulum import pendulum_metrics


def _columns(t, psi_deg):
    n = len(t)
    zero = np.zeros(n)
    return {"t": np.asarray(t, dtype=float), "psi": np.radians(np.asarray(psi_deg, dtype=float)), "phi": zero,
            "x": zero, "y": zero, "x_d": zero, "y_d": zero, "v_l": zero, "i_l": zero, "v_r": zero, "i_r": zero}


def test_a_sample_one_nanosecond_into_the_last_second_is_in_it():
    """A 0.09 deg spike at t_end - 1 + 1e-9 (computed as the window's edge is) is the last
    second's peak; the same spike at t_end - 1 exactly is not.  Catches ``>`` for ``>=``."""
    end = 5.0
    edge = end - 1.0 + 1e-9
    t = [0.0, 1.0, end - 1.0, edge, 4.5, end]
    m = pendulum_metrics(_columns(t, [0.5, 0.01, 0.01, 0.09, 0.02, 0.01]), 0.002)
    assert m["last_second_pitch_deg"] == pytest.approx(0.09, rel=1e-12)
    m = pendulum_metrics(_columns(t, [0.5, 0.01, 0.09, 0.01, 0.02, 0.01]), 0.002)
    assert m["last_second_pitch_deg"] == pytest.approx(0.02, rel=1e-12)
