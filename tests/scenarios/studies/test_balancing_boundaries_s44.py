"""scenarios/studies/balancing.py ``measure`` at the edges of its window and of its saturation
test (issue 31, training sweep s44: compare mutants at balancing.py:48 and :58; the window is
scenarios.run.metrics.in_window since session 44).

The window is the scene's [start, end] widened by 1e-9 s for the rounding of the time grid,
as scene_metrics' (scenarios.run.metrics.in_window): a sample up to 1e-9 s outside an end is
in it, one 2e-9 s outside is not (the closed interval [start - 1e-9, end + 1e-9]).  A drive is saturated at a sample when its |v| is at
least v_max (1 - 1e-9): the limit itself less a relative 1e-9 for the rounding of the clamp.
The run is given here (run_scene replaced), as in test_balancing_rows.py.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from motor import get_motor_preset
from scenarios.studies import balancing

START, END = 1.0, 3.0


def _run(monkeypatch):
    """Samples at both sides of each widened end; each one's torque tells whether it was taken."""
    v_max = get_motor_preset("motor1").v_max
    saturated = v_max * (1 - 1e-9)
    t = np.array([0.5, START - 2e-9, START - 1e-9, 1.5, 2.0, 2.5, END + 1e-9, END + 2e-9, 3.5])
    columns = {"t": t,
               "tau1": np.array([0.0, 9.0, 2.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0]),
               "tau2": np.array([0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 3.0, 8.0, 0.0]),
               "i1": np.zeros(t.size), "i2": np.zeros(t.size),
               "v1": np.array([v_max, v_max, 0.0, np.nextafter(saturated, 0.0), saturated, 0.0, 0.0, v_max, v_max]),
               "v2": np.zeros(t.size)}
    outcome = SimpleNamespace(columns=columns, metrics={"e_ef_mm": 1.0, "tau_ef_Nm": 1.0},
                              scene=SimpleNamespace(window=(START, END)), result=SimpleNamespace(error=""))
    monkeypatch.setattr(balancing, "run_scene", lambda scene: outcome)
    return balancing.measure("TCMDx", 1.0, False)[0]


def test_a_sample_exactly_1e9_s_outside_an_end_is_in_the_window_and_one_further_is_out(monkeypatch):
    """The torque peaks are those of the five samples in the window: 2 N m at 1 ns before the
    start (taken), not 9 N m at 2 ns before it; 3 N m at 1 ns after the end, not 8 at 2 ns."""
    row = _run(monkeypatch)
    assert row["tau1_peak_Nm"] == 2.0
    assert row["tau2_peak_Nm"] == 3.0


def test_a_voltage_of_exactly_v_max_less_1e9_relative_is_saturated_and_one_double_below_is_not(monkeypatch):
    """Of the five samples in the window, one is at v_max (1 - 1e-9) exactly (saturated) and one
    a double below it (not): 20 % saturated; the peak is that one sample's voltage."""
    row = _run(monkeypatch)
    assert row["saturated_pct"] == pytest.approx(20.0, rel=1e-12)
    assert row["v_peak_V"] == get_motor_preset("motor1").v_max * (1 - 1e-9)
