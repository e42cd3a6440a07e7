"""The trade study's bookkeeping at its edges, hit exactly, on runs made up here (issue 31,
session 44: boundaries of the generalised training sample): a setting whose best time is
exactly REPEAT_BELOW_S is run again; a row with a zero wall time or error has no ratio."""
from __future__ import annotations

import importlib
import math

import numpy as np

from scenarios.scenes import get_scene
from scenarios.studies.trade.settings import Setting

#: The module (the package's name ``measure`` is its function).
trade = importlib.import_module("scenarios.studies.trade.measure")


class _Run:
    def __init__(self, time, signals, extra=None):
        self.time, self.signals, self.columns = np.asarray(time), signals, {}
        self.extra, self.error, self.completed = dict(extra or {}), None, True

    def __getitem__(self, signal):
        return self.signals[signal]


def test_a_setting_whose_first_run_took_exactly_the_repeat_bound_runs_every_round(monkeypatch):
    """"a run longer than REPEAT_BELOW_S runs once": one of exactly 5 s is not longer, so it runs
    in all three rounds and its best time counts (4 s); one a float longer runs once.
    Catches ``>=`` for ``>``."""
    assert trade.REPEAT_BELOW_S == 5.0
    scene = get_scene("thesis_sim_circle")
    walls = {"edge": [5.0, 4.0, 4.5], "over": [math.nextafter(5.0, 6.0), 1.0, 1.0]}
    calls = {name: 0 for name in walls}

    def fake_run(setting, s):
        if s.system.stop_time <= trade.WARM_UP_S:     # the warm-up run, not timed
            return None, "warm-up"
        calls[setting.name] += 1
        wall = walls[setting.name][calls[setting.name] - 1]
        return _Run(np.arange(3) * 1e-3, {sig: np.zeros(3) for sig in s.system.record},
                    extra={"call_s": wall, "cpu_s": wall / 2}), None

    monkeypatch.setattr(trade, "_run_setting", fake_run)
    monkeypatch.setattr(trade, "measure", lambda result, reference, s: {"rms_err_m": 1e-6})
    monkeypatch.setattr(trade, "scene_metrics", lambda *args: {"e_ef_mm": 0.5})
    rows, _ = trade._sweep(scene, [Setting(name, "accuracy", name, lambda s: s) for name in walls], None, 3,
                           lambda text: None)
    assert calls == {"edge": 3, "over": 1}
    assert rows[0]["wall_s"] == 4.0 and rows[1]["wall_s"] == math.nextafter(5.0, 6.0)


def test_a_zero_wall_time_or_error_gives_no_speedup_or_gain_and_the_smallest_positive_ones_do():
    """speedup = the defaults' wall / the row's, gain = the defaults' error / the row's, each only
    for a positive denominator (NaN for 0); 1e-300 is positive.  Catches ``>=`` for ``>``."""
    def row(name, wall, err):
        return {"setting": name, "kind": "accuracy", "wall_s": wall, "rms_err_m": err, "error": ""}

    rows = [row("defaults", 2.0, 1e-6), row("zero", 0.0, 0.0), row("tiny", 1e-300, 1e-300)]
    trade._relative(rows)
    assert math.isnan(rows[1]["speedup"]) and math.isnan(rows[1]["gain"])
    assert rows[2]["speedup"] == 2.0 / 1e-300 and rows[2]["gain"] == 1e-6 / 1e-300
    assert rows[0]["speedup"] == 1.0 and rows[0]["gain"] == 1.0
