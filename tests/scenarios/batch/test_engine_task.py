"""scenarios/batch/engine.py's task run in this process (the engine's dask runs are of the slow
kind): a run that cannot start is a result naming the error, with NaN where numbers belong; one
that runs gives its scene's metrics, files written where asked (issue 31: the scenarios' weakest
area)."""
from __future__ import annotations

import json
import math
from dataclasses import replace

from scenarios.batch.engine import Task, default_workers, run_task
from scenarios.scenes import get_scene


def _short(stop=0.02):
    scene = get_scene("bench_circle_TCMDx")
    return replace(scene, system=replace(scene.system, stop_time=stop))


def test_a_task_that_cannot_start_is_a_result_with_its_error_and_no_numbers(tmp_path):
    """Its output folder is a file: the run cannot start.  Catches the exception escaping, the
    error without its type or message, a number that is not NaN."""
    blocked = tmp_path / "file"
    blocked.write_text("")
    result = run_task(Task("k", _short(), out_dir=str(blocked / "run")))
    assert result["scene"] == "bench_circle_TCMDx" and result["completed"] is False and result["settled"] is False
    assert result["outcome"] == "failed" and result["error"]["kind"] == "failed"
    assert result["error"]["message"].startswith("WriteError: ")
    assert f"output directory {blocked / 'run'} is not writable" in result["error"]["message"]
    for key in ("e_ef_mm", "tau_ef_Nm", "e_ss_mm", "e_ss_1s_mm", "t_settle_s", "wall_s"):
        assert math.isnan(result[key]), key


def test_a_task_runs_its_scene_and_writes_its_files_where_asked(tmp_path):
    """20 ms of the bench circle at 2 ms: the metrics of that run (simulated to the stop, the
    windows not reached NaN), result.csv and metrics.json in out_dir and no plot unless asked.
    Catches the task's mode, out_dir or plots not passed to the run."""
    scene = _short()
    scene = replace(scene, system=replace(scene.system, step=2e-3, components=tuple(
        replace(c, parameters={**c.parameters, "T": 2e-3}) if "T" in c.parameters or c.model in (
            "Derivator", "DCMotorDrive", "PositionController", "CurrentObserver") else c
        for c in scene.system.components)))
    out = tmp_path / "run"
    result = run_task(Task("k", scene, mode="inprocess", out_dir=str(out)))
    assert result["completed"] is True and "error" not in result and result["mode"] == "inprocess"
    assert result["simulated_s"] == scene.system.stop_time and math.isnan(result["e_ef_mm"])
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "result.csv"]
    assert json.loads((out / "metrics.json").read_text())["simulated_s"] == result["simulated_s"]
    rows = (out / "result.csv").read_text().splitlines()
    assert len(rows) == 1 + 11 and rows[-1].startswith("0.02")          # t = 0, 2, ..., 20 ms
    assert default_workers() >= 1
