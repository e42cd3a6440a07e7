"""scenarios/batch/sweep.py's ``run_sweep`` with the cluster replaced by a made-up one (the real
sweeps are of the slow kind): tasks finishing in reverse order, one run stopped; the rows by
sample with each sample's own draw and metrics, sweep.csv and summary.json read back exactly, a
continued sweep running only the missing samples and keeping the old rows, another sweep's
folder and bad N or seed refused (issue 31: the scenarios' weakest area; every written value
read back)."""
from __future__ import annotations

import json
import math

import pytest

from scenarios.batch import sweep as sweep_module
from scenarios.batch.sweep import columns, read_rows, run_sweep, summarize
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.perturb import draw, perturbable, uncertainties


def _metrics(i: int) -> dict:
    if i == 2:
        return {"completed": False, "outcome": "refused", "e_ef_mm": math.nan, "tau_ef_Nm": math.nan,
                "e_ss_mm": math.nan, "e_ss_1s_mm": math.nan, "t_settle_s": math.nan, "wall_s": 0.5,
                "error": {"kind": "refused", "message": "plant refused", "instance": "plant", "time": 0.25,
                          "variable": "q1", "value": 7.5, "unit": "rad", "code": 3, "reason": "r"}}
    return {"completed": True, "outcome": "completed", "e_ef_mm": 0.5 + 0.125 * i, "tau_ef_Nm": 0.01 * i,
            "e_ss_mm": 1e-3 * i, "e_ss_1s_mm": math.nan, "t_settle_s": 0.25 * i, "wall_s": 1.0 + i, "error": None}


@pytest.fixture
def cluster(monkeypatch):
    """run_tasks replaced: each task's metrics by its sample, in reverse order; the keys run."""
    ran = []

    def run_tasks(tasks, on_result=None, progress=None, **kwargs):
        for task in reversed(tasks):
            ran.append(task.key)
            on_result(task, _metrics(int(task.key.removeprefix("sample"))))
        return {}

    monkeypatch.setattr(sweep_module, "run_tasks", run_tasks)
    return ran


def _expected_row(i, parameters, spread, seed=7):
    m = _metrics(i)
    error = m["error"] or {}
    return {"sample": i, **draw(parameters, spread, seed, i, "uniform"), **{k: m[k] for k in sweep_module.METRICS},
            "completed": m["completed"], "outcome": m["outcome"], "error_instance": error.get("instance", ""),
            "error_time": error.get("time", math.nan), "error_variable": error.get("variable", ""),
            "error_value": error.get("value", math.nan), "error_unit": error.get("unit", ""),
            "error_code": error.get("code"), "error_reason": error.get("reason", ""),
            "error": error.get("message", ""), "wall_s": m["wall_s"]}


def _same(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(
        (isinstance(v, float) and math.isnan(v) and isinstance(b[k], float) and math.isnan(b[k])) or v == b[k]
        for k, v in a.items())


def test_rows_files_and_a_continued_sweep(cluster, tmp_path):
    """Catches a row's values of another sample (the tasks finish in reverse), the csv in
    completion order or not read back as written, the summary not over the rows, a continued
    sweep running samples it has or losing their rows."""
    scene = get_scene("bench_circle_PDq")
    parameters = perturbable(scene)
    spread = uncertainties(parameters, 0.05, None)
    names = [p.name for p in parameters]
    out = tmp_path / "sweep"
    first = run_sweep(scene, 4, 0.05, seed=7, out_dir=out, plots=False)
    assert cluster == ["sample3", "sample2", "sample1", "sample0"] and first.computed == [0, 1, 2, 3]
    assert [r["sample"] for r in first.rows] == [0, 1, 2, 3]
    for i, row in enumerate(first.rows):
        assert _same(row, _expected_row(i, parameters, spread)), i
    back = read_rows(out / "sweep.csv", columns(names))
    assert len(back) == 4 and all(_same(b, r) for b, r in zip(back, first.rows))
    assert json.loads((out / "summary.json").read_text()) == json.loads(json.dumps(summarize(first.rows)))
    assert first.summary["e_ef_mm"]["n"] == 3
    settings = json.loads((out / "sweep.json").read_text())
    assert (settings["samples"], settings["seed"], settings["parameters"]) == (4, 7, names)

    cluster.clear()
    more = run_sweep(scene, 6, 0.05, seed=7, out_dir=out, plots=False)
    assert cluster == ["sample5", "sample4"] and more.computed == [4, 5]
    assert all(_same(a, b) for a, b in zip(more.rows[:4], first.rows))
    assert _same(more.rows[5], _expected_row(5, parameters, spread))
    assert [r["sample"] for r in read_rows(out / "sweep.csv", columns(names))] == [0, 1, 2, 3, 4, 5]


def test_another_sweeps_folder_and_bad_settings_are_refused(cluster, tmp_path):
    """Catches a folder holding another seed's sweep continued, and N < 1 or a negative seed run."""
    scene = get_scene("bench_circle_PDq")
    run_sweep(scene, 1, 0.05, seed=7, out_dir=tmp_path, plots=False)
    with pytest.raises(ValueError, match=rf"{tmp_path} holds a sweep with seed = 7, not 8: continue it with the same"):
        run_sweep(scene, 1, 0.05, seed=8, out_dir=tmp_path, plots=False)
    with pytest.raises(ValueError, match=r"^samples = 0 must be an integer >= 1$"):
        run_sweep(scene, 0, 0.05)
    with pytest.raises(ValueError, match=r"^seed = -1 must be an integer >= 0$"):
        run_sweep(scene, 1, 0.05, seed=-1)
    assert cluster == ["sample0"]
