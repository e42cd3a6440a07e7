"""The trade study's sweep bookkeeping (scenarios/studies/trade/measure.py) on runs made up here:
what each run records, which settings are run again in later rounds, which timing counts, and
the encoder columns when only one side recorded the encoders."""
from __future__ import annotations

import importlib
from types import SimpleNamespace

import numpy as np
import pytest

from scenarios.scenes import get_scene
from scenarios.studies.trade.settings import Setting

#: The module (the package's name ``measure`` is its function).
trade = importlib.import_module("scenarios.studies.trade.measure")


class _Run:
    def __init__(self, time, signals, columns=None, extra=None):
        self.time, self.signals, self.columns = np.asarray(time), signals, columns or {}
        self.extra, self.error, self.completed = dict(extra or {}), None, True

    def __getitem__(self, signal):
        return self.signals[signal]


def test_each_run_records_the_scene_columns_and_the_plants_position_encoders_and_residual():
    """The sweep's systems record what they recorded, the scene's columns and the plant's x, y,
    encoder readings and residual, each once, in that order.  Catches the plant's signals left out
    (or the list dropped) and duplicates."""
    scene = get_scene("bench_circle_TCMDx")
    record = trade._with_record(scene.system, "plant", scene.columns).record
    assert len(record) == len(set(record))
    expected = list(dict.fromkeys([*scene.system.record, *scene.columns.values(), "plant.x", "plant.y",
                                   "plant.q1_enc", "plant.q2_enc", "plant.residual"]))
    assert list(record) == expected
    assert trade._with_record(scene.system, None, {"a": "ctrl.e1"}).record == tuple(
        dict.fromkeys([*scene.system.record, "ctrl.e1"]))


def _encoder_run(time, q1, q2):
    n = len(time)
    return _Run(time, {"plant.x": np.zeros(n), "plant.y": np.zeros(n), "plant.q1_enc": np.asarray(q1, float),
                       "plant.q2_enc": np.asarray(q2, float), "plant.residual": np.linspace(0.0, -3e-9, n)})


def test_encoder_differences_are_counted_only_when_both_runs_recorded_the_encoders():
    """A run at 2 ms against a 1 ms reference: its encoders differ from the reference's at the
    common rows t = 4 and 8 ms (2 samples, the first at 4 ms); the residual is its largest |value|.
    When the reference has no encoder signals the columns stay empty (no lookup of a missing
    signal).  Catches the reference's signals checked on the run instead."""
    scene = get_scene("bench_circle_TCMDx")
    t_ref, t_run = np.arange(11) * 1e-3, np.arange(6) * 2e-3
    reference = _encoder_run(t_ref, np.zeros(11), np.zeros(11))
    run = _encoder_run(t_run, [0, 0, 1e-4, 0, 0, 0], [0, 0, 0, 0, -1e-4, 0])
    row = trade.measure(run, reference, scene)
    assert (row["enc_diff"], row["enc_first_s"]) == (2, pytest.approx(4e-3, abs=1e-15))
    assert row["residual_m"] == pytest.approx(3e-9, rel=1e-12)
    del reference.signals["plant.q1_enc"]
    row = trade.measure(run, reference, scene)
    assert row["enc_diff"] == "" and np.isnan(row["enc_first_s"])


def test_a_slow_setting_runs_once_and_a_fast_one_every_round_its_best_time_counting(monkeypatch):
    """Three rounds: a setting whose first run took longer than REPEAT_BELOW_S runs once (after its
    warm-up), a fast one three times and its row holds its fastest wall and CPU time; a setting
    that failed is not retried.  Catches the repeat rule starting a round late (a slow setting
    run twice) or the first of the timings counting."""
    scene = get_scene("thesis_sim_circle")
    walls = {"slow": [9.0, 7.0, 6.0], "fast": [0.3, 0.2, 0.25], "broken": []}
    calls = {name: 0 for name in walls}

    def fake_run(setting, s):
        if s.system.stop_time <= trade.WARM_UP_S:     # the warm-up run, not timed
            return None, "warm-up"
        calls[setting.name] += 1
        if setting.name == "broken":
            return None, "RuntimeError: no"
        wall = walls[setting.name][calls[setting.name] - 1]
        n = 3
        return _Run(np.arange(n) * 1e-3, {sig: np.zeros(n) for sig in s.system.record},
                    extra={"call_s": wall, "cpu_s": wall / 2}), None

    monkeypatch.setattr(trade, "_run_setting", fake_run)
    monkeypatch.setattr(trade, "measure", lambda result, reference, s: {"rms_err_m": 1e-6})
    monkeypatch.setattr(trade, "scene_metrics", lambda *args: {"e_ef_mm": 0.5})
    chosen = [Setting(name, "accuracy", name, lambda s: s) for name in walls]
    said = []
    rows, skipped = trade._sweep(scene, chosen, None, 3, said.append)
    assert calls == {"slow": 1, "fast": 3, "broken": 1} and skipped == []
    assert [r["setting"] for r in rows] == ["slow", "fast", "broken"]
    assert (rows[0]["wall_s"], rows[0]["cpu_s"]) == (9.0, 4.5)
    assert (rows[1]["wall_s"], rows[1]["cpu_s"]) == (0.2, 0.1)
    assert rows[2]["error"] == "RuntimeError: no" and np.isnan(rows[2]["wall_s"])
    assert len(said) == 3 and "RuntimeError: no" in said[2]


def test_the_encoders_are_those_of_the_plant_the_reference_names():
    """A plant instance named ``arm`` (not ``plant``): the reference run (a ReferenceResult, which
    names its plant) and the run both record ``arm.*``; the encoders still compare, 1 sample
    apart at t = 2 ms, and the deviation is the axle's 3-4-5 offset.  Catches the plant's name
    read from the run (a master Result, which names none: ``plant.q1_enc`` looked up)."""
    from scenarios.reference import ReferenceResult

    t = np.arange(4) * 1e-3
    signals = {"arm.x": np.zeros(4), "arm.y": np.zeros(4), "arm.q1_enc": np.zeros(4), "arm.q2_enc": np.zeros(4)}
    reference = ReferenceResult(t, signals, {"t": t}, ("arm",), "exact", "RK45", 1e-9, 1e-9, 1.0,
                                extra={"plant": "arm"})
    run = _Run(t, {**signals, "arm.x": np.full(4, 3e-3), "arm.y": np.full(4, 4e-3),
                   "arm.q2_enc": np.array([0.0, 0.0, 1e-4, 0.0])})
    scene = SimpleNamespace(system=SimpleNamespace(components=(SimpleNamespace(name="arm", model="FiveBarPlant"),)),
                            columns={})
    row = trade.measure(run, reference, scene)
    assert (row["enc_diff"], row["enc_first_s"]) == (1, 2e-3)
    assert row["rms_err_m"] == pytest.approx(5e-3, rel=1e-12)


def test_a_setting_runs_its_mode_and_coupling_and_a_run_that_cannot_start_is_its_message(monkeypatch):
    """``_run_setting``: the scene's system run in the setting's mode and coupling, its call and
    CPU times stored on the result; a run that raises gives no result and the exception's type
    and message.  Catches the setting's mode or coupling not passed on, the exception ending
    the sweep."""
    scene = get_scene("thesis_sim_circle")
    asked = []

    def simulate(system, mode, coupling):
        asked.append((system, mode, coupling))
        if coupling == "jacobi":
            raise OSError("the FMU did not build")
        return _Run(np.arange(3) * 1e-3, {})

    monkeypatch.setattr(trade, "simulate", simulate)
    setting = Setting("s", "accuracy", "s", lambda s: s, mode="fmu", coupling="gauss-seidel")
    result, failure = trade._run_setting(setting, scene)
    assert failure is None and asked == [(scene.system, "fmu", "gauss-seidel")]
    assert result.extra["call_s"] >= 0.0 and result.extra["cpu_s"] >= 0.0
    broken = Setting("b", "accuracy", "b", lambda s: s, coupling="jacobi")
    assert trade._run_setting(broken, scene) == (None, "OSError: the FMU did not build")


def test_a_setting_that_does_not_apply_is_skipped_and_a_run_that_stopped_keeps_its_error(monkeypatch):
    """A setting whose scene is None (it does not apply) is neither run nor a row, but listed as
    skipped; a run that stopped with an error is measured and its row carries the error; every
    setting runs a warm-up first, cut at WARM_UP_S.  Catches a skipped setting run or lost, the
    run's error dropped from its row, the warm-up run whole."""
    scene = get_scene("thesis_sim_circle")
    stops = []

    class Stopped(_Run):
        def __init__(self):
            super().__init__(np.arange(3) * 1e-3, {sig: np.zeros(3) for sig in scene.system.record},
                             extra={"call_s": 0.5, "cpu_s": 0.25})
            self.error = "plant refused the step from t = 0.002 s"

    def fake_run(setting, s):
        stops.append((setting.name, s.system.stop_time))
        return Stopped(), None

    monkeypatch.setattr(trade, "_run_setting", fake_run)
    monkeypatch.setattr(trade, "measure", lambda result, reference, s: {"rms_err_m": 1e-6})
    monkeypatch.setattr(trade, "scene_metrics", lambda *args: {"e_ef_mm": 0.5})
    chosen = [Setting("no", "fidelity", "no", lambda s: None), Setting("yes", "accuracy", "yes", lambda s: s)]
    rows, skipped = trade._sweep(scene, chosen, None, 1, lambda text: None)
    assert skipped == ["no"] and [r["setting"] for r in rows] == ["yes"]
    assert stops == [("yes", min(scene.system.stop_time, trade.WARM_UP_S)), ("yes", scene.system.stop_time)]
    assert rows[0]["error"] == "plant refused the step from t = 0.002 s"
    assert (rows[0]["wall_s"], rows[0]["cpu_s"], rows[0]["rms_err_m"], rows[0]["e_ef_mm"]) == (0.5, 0.25, 1e-6, 0.5)


def test_two_runs_of_one_setting_that_differ_stop_the_sweep_naming_it(monkeypatch):
    """The study times the best of several identical runs: a setting whose second run moves the
    plant differently is refused by name.  Catches the check comparing a run with itself or
    with the warm-up."""
    scene = get_scene("thesis_sim_circle")
    runs = iter([0.0, 0.0, 1e-9])       # the warm-up, the first round, the second round

    def fake_run(setting, s):
        x = next(runs)
        return _Run(np.arange(3) * 1e-3, {**{sig: np.zeros(3) for sig in s.system.record}, "plant.x": np.full(3, x)},
                    extra={"call_s": 0.1, "cpu_s": 0.1}), None

    monkeypatch.setattr(trade, "_run_setting", fake_run)
    with pytest.raises(RuntimeError, match=r"^fast: two runs of the same setting differ$"):
        trade._sweep(scene, [Setting("fast", "accuracy", "fast", lambda s: s)], None, 2, lambda text: None)
