"""scenarios/studies/pendulum_trade.py's rows without its long runs (run_scene replaced by one
that records the scene and gives metrics set here): the sample-time sweep builds each scene at
its T with the plant's RK4 at 0.5 ms, the battery sweep sets its voltage, and each row reads
the metrics (issue 31: sample times other than 1 ms; the scenarios' weakest area)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from scenarios.studies import pendulum_trade


@pytest.fixture
def runs(monkeypatch):
    asked = []

    def run_scene(scene):
        asked.append(scene)
        last = 0.05 if len(asked) % 2 else 0.5                     # balanced, then not
        metrics = {"completed": True, "peak_pitch_deg": 5.0 + len(asked), "last_second_pitch_deg": last}
        return SimpleNamespace(metrics=metrics, columns={"v_l": np.array([0.5, -3.25, 2.0])})

    monkeypatch.setattr(pendulum_trade, "run_scene", run_scene)
    return asked


def test_the_sample_time_sweep_runs_each_T_with_the_plant_at_half_a_millisecond(runs):
    """Catches T reaching the master's step but not the controller (or the reverse), the
    plant's sub-steps not T / 0.5 ms, a row's balance read from another metric."""
    rows = pendulum_trade.sample_time_rows((2e-3, 7.5e-3, 0.25e-3))
    assert [r["T_ms"] for r in rows] == [2.0, 7.5, 0.25]
    for scene, T, substeps in zip(runs, (2e-3, 7.5e-3, 0.25e-3), (4, 15, 1)):
        assert scene.name == "pendulum_balance" and scene.system.step == T
        assert scene.system.component("ctrl").parameters["T"] == T
        assert scene.system.component("plant").parameters["substeps"] == substeps
    assert [r["balanced"] for r in rows] == [True, False, True]
    assert rows[1] == {"T_ms": 7.5, "balanced": False, "completed": True, "peak_pitch_deg": 7.0,
                       "last_second_pitch_deg": 0.5, "error": ""}


def test_the_battery_sweep_sets_the_voltage_of_the_controller_and_both_drives(runs):
    """Catches the battery sweep setting the voltage on the controller alone (the drives still saturating
    at the old value), or on one drive."""
    rows = pendulum_trade.battery_rows((1.45, 8.0))
    for scene, v in zip(runs, (1.45, 8.0)):
        assert scene.system.component("ctrl").parameters["v_battery"] == v
        assert {scene.system.component(d).parameters["v_max"] for d in ("drive_l", "drive_r")} == {v}
    assert rows[0]["v_battery"] == 1.45 and rows[0]["peak_voltage"] == 3.25 and rows[0]["balanced"] is True


def test_balanced_needs_a_completed_run_within_the_band_over_the_last_second():
    """Catches a stopped run counted as balanced, or the band's edge tested with the wrong inequality."""
    assert pendulum_trade.balanced({"completed": True, "last_second_pitch_deg": 0.1})
    assert not pendulum_trade.balanced({"completed": True, "last_second_pitch_deg": 0.1000001})
    assert not pendulum_trade.balanced({"completed": False, "last_second_pitch_deg": 0.0})


def test_markdown_has_a_row_per_setting_with_four_digits():
    rows = [{"setting": "yaw off", "wall_s": 1.23456, "completed": True}, {"setting": "x", "wall_s": 2.0,
                                                                          "completed": False}]
    assert pendulum_trade.markdown(rows).splitlines() == [
        "| setting | wall_s | completed |", "|---|---|---|", "| yaw off | 1.235 | True |", "| x | 2 | False |"]
