"""scenarios/studies/pendulum_trade.py's turning window (6-8 s) at its ends, hit exactly (issue 31,
session 44: boundaries of the generalised training sample): ``drive_comparison`` with
``run_scene`` replaced by runs whose pitch differs only at one sample."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from scenarios.studies import pendulum_trade


def _comparison(monkeypatch, at: float, gap_deg: float) -> dict:
    """The seed model's pitch off the exact one's by ``gap_deg`` at t = ``at`` only (a 0.5 s grid)."""
    t = np.arange(0.0, 10.001, 0.5)

    def run_scene(scene):
        seed = scene.system.component("plant").parameters["model"] == "seed"
        psi = np.radians(0.2 * np.sin(t)) + (np.radians(gap_deg) * (t == at) if seed else 0.0)
        columns = {"t": t, "x": 0.1 * t, "y": 0.0 * t, "psi": psi, "x_d": 0.1 * t, "y_d": 0.0 * t}
        return SimpleNamespace(columns=columns, metrics={"final_position_error_mm": 0.0})

    monkeypatch.setattr(pendulum_trade, "run_scene", run_scene)
    return pendulum_trade.drive_comparison()


@pytest.mark.parametrize("at", [6.0, 8.0])
def test_the_turning_windows_ends_are_in_it(monkeypatch, at):
    """A pitch gap at exactly 6 s or 8 s is the turning window's largest.  Catches a strict
    comparison at either end."""
    out = _comparison(monkeypatch, at, 0.4)
    assert out["max_pitch_gap_turning_deg"] == pytest.approx(0.4, rel=1e-12)
    assert out["max_pitch_gap_deg"] == pytest.approx(0.4, rel=1e-12)


@pytest.mark.parametrize("at", [5.5, 8.5])
def test_a_gap_half_a_second_outside_the_turning_window_is_not_in_it(monkeypatch, at):
    out = _comparison(monkeypatch, at, 0.4)
    assert out["max_pitch_gap_turning_deg"] == 0.0 and out["max_pitch_gap_deg"] == pytest.approx(0.4, rel=1e-12)
