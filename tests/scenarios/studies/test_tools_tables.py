"""scenarios/studies/tools.py's numbers without running a tool (its own tests are of the slow
kind): a tool's run at 0.5 ms read at the scene's 2 ms communication points, the metrics of
those rows against scene_metrics of the same rows taken by index, and the comparison tables'
ratios and CPU figures against the numbers computed here (issue 31: a second sample time,
values compared with an independent computation)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from fmus.ssp.run import SspRun
from fmus.status import RunError, RunStatus
from scenarios.run.metrics import scene_metrics
from scenarios.scenes import get_scene
from scenarios.studies import tools

H = 2e-3


def _scene():
    scene = get_scene("bench_circle_TCMDx")
    return replace(scene, system=replace(scene.system, step=H, stop_time=0.2), window=(0.05, 0.15))


def _run(error=None, end=0.2):
    """A tool's run at 0.5 ms, its times summed as t + h (off k h by ulps); package signals."""
    n = int(round(end / 5e-4)) + 1
    t = np.cumsum(np.full(n, 5e-4)) - 5e-4
    signals = {"plant.x": 0.01 * np.sin(7 * t), "plant.y": 0.1 + 0.002 * t, "traj.x_d": 0.01 * np.sin(7 * t + 0.01),
               "traj.y_d": np.full(n, 0.1), "ctrl.tau1": 0.02 * np.cos(t), "ctrl.tau2": -0.01 + t,
               "plant.q1": t}
    return SspRun(t, signals, "fmpy", wall_s=0.8, error=error, extra={"cpu_s": 0.5})


COLUMNS = {"plant.x": "x", "plant.y": "y", "traj.x_d": "x_d", "traj.y_d": "y_d", "ctrl.tau1": "tau1",
           "ctrl.tau2": "tau2", "plant.q1": "q1"}


def test_a_tools_finer_rows_are_read_at_the_scenes_2ms_points():
    """Every 4th row of the 0.5 ms run (101 of 401): its metrics are scene_metrics of those rows.
    Catches the rows read at the tool's own step, at 1 ms (the default), or by exact equality
    of the summed times (none would match), a column not among the metric's kept."""
    scene, run = _scene(), _run()
    got = tools.tool_metrics(scene, run, COLUMNS)
    rows = np.arange(0, 401, 4)
    data = {"t": run.time[rows], **{name: run[signal][rows] for signal, name in COLUMNS.items() if name != "q1"}}
    expected = scene_metrics(scene, data, 0.8, True)
    assert got["completed"] is True and got["simulated_s"] == pytest.approx(0.2, abs=1e-12)
    for key in ("e_ef_mm", "tau_ef_Nm", "e_max_mm", "realtime_factor"):
        assert got[key] == pytest.approx(expected[key], rel=1e-12), key
    assert got["e_ef_mm"] > 0.0


def test_a_run_that_stopped_early_or_failed_is_not_completed():
    """Catches a tool's run that stopped before its end, or carries an error, counted as completed."""
    scene = _scene()
    assert tools.tool_metrics(scene, _run(end=0.1), COLUMNS)["completed"] is False
    refused = RunError(RunStatus.REFUSED, "plant refused the step from t = 0.1 s: singular", instance="plant", time=0.1)
    assert tools.tool_metrics(scene, _run(error=refused), COLUMNS)["completed"] is False


def test_a_stored_runs_error_reads_back_as_its_record(tmp_path):
    """Catches a tool's error stored as text (or not stored: json cannot write a RunError) and
    read back as a string or a dict: the rows of the stored runs carry the same record."""
    error = RunError(RunStatus.REFUSED, "plant refused the step from t = 0.1 s: singular", instance="plant",
                     time=0.1, variable="det", value=-1e-4, unit="", code=4, reason="singular")
    results = tmp_path / "tools.json"
    tools._store(results, tools._key("ours", "bench_circle_TCMDx", "parcosim"), {"e_ef_mm": 0.5})
    tools._store(results, tools._key("default", "bench_circle_TCMDx", "ecos"), {"metrics": None, "error": error.record()})
    stored = tools.load_results(results)
    (tool, _, _, read), = tools.stored_rows(stored)[("default", "bench_circle_TCMDx")]
    assert tool == "ecos" and read == error


def _results():
    ours = {"e_ef_mm": 0.5, "tau_ef_Nm": 0.02}
    fmpy = {"e_ef_mm": 0.55, "tau_ef_Nm": 0.021, "completed": True, "cpu_s": 0.3, "simulated_s": 0.2, "step": H}
    ecos = {"e_ef_mm": 0.45, "tau_ef_Nm": 0.019, "completed": True, "cpu_s": 0.6, "simulated_s": 0.2, "step": 1e-3}
    return {("default", "bench_circle_TCMDx"): [("fmpy", fmpy, ours, None), ("ecos", ecos, ours, None),
                                                ("libcosim", None, ours, RunError(RunStatus.FAILED, "RuntimeError: no"))]}


def test_the_comparison_table_gives_each_tools_ratios_step_and_cpu():
    """e_ef 0.55 against ours 0.5: 1.1000; CPU 0.3 s over 200 simulated ms: 1500 µs a ms.
    Catches a ratio inverted, the CPU per ms off by 1000, a failed tool's row lost."""
    lines = tools.table(_results()).splitlines()
    assert lines[2] == "| default | bench_circle_TCMDx | fmpy | 2 | 0.55 (0.5) | 1.1000 | 1.0500 | yes | 1500 |"
    assert lines[3] == "| default | bench_circle_TCMDx | ecos | 1 | 0.45 (0.5) | 0.9000 | 0.9500 | yes | 3000 |"
    assert lines[4] == "| default | bench_circle_TCMDx | libcosim | – | – (0.5) | – | – | no: RuntimeError: no | – |"


def test_a_run_shorter_than_a_millisecond_is_charged_its_cpu_over_one_millisecond():
    """CPU per simulated ms for runs that stopped early: 3 ms of CPU over 0.5 ms simulated (or
    none) count over one ms (3000 µs), not over the fraction (6000 µs, or a division by zero);
    over 4 ms, 750 µs; a run without a CPU figure, "–"; no step stored: 1 ms; a tool's run
    without a key (a plain scene name) is of the default kind.  Catches the floor of one ms
    changed or dropped, the CPU time taken in ms, a stored step ignored."""
    ours = {"e_ef_mm": 0.5, "tau_ef_Nm": 0.02}
    base = {"e_ef_mm": 1.0, "tau_ef_Nm": 0.04, "completed": False}
    rows = [("fmpy", {**base, "cpu_s": 3e-3, "simulated_s": 5e-4}, ours, "stopped"),
            ("ecos", {**base, "cpu_s": 3e-3, "simulated_s": 0.0}, ours, "stopped"),
            ("libcosim", {**base, "cpu_s": 3e-3, "simulated_s": 4e-3, "step": 2.5e-4}, ours, "stopped"),
            ("fmpy", {**base, "simulated_s": 4e-3}, ours, "stopped")]
    lines = tools.table({"bench_circle_TCMDx": rows}).splitlines()[2:]
    assert lines == ["| default | bench_circle_TCMDx | fmpy | 1 | 1 (0.5) | 2.0000 | 2.0000 | no: stopped | 3000 |",
                     "| default | bench_circle_TCMDx | ecos | 1 | 1 (0.5) | 2.0000 | 2.0000 | no: stopped | 3000 |",
                     "| default | bench_circle_TCMDx | libcosim | 0.25 | 1 (0.5) | 2.0000 | 2.0000 | no: stopped "
                     "| 750 |",
                     "| default | bench_circle_TCMDx | fmpy | 1 | 1 (0.5) | 2.0000 | 2.0000 | no: stopped | – |"]


def test_the_summary_gives_each_tools_ranges_over_the_scenes():
    """Catches the summary's ranges, completion counts or CPU figures computed over the wrong rows, or a
    tool that never ran given numbers."""
    results = _results()
    results[("default", "bench_triangle_TCMDx")] = [
        ("fmpy", {"e_ef_mm": 0.8, "tau_ef_Nm": 0.03, "completed": True, "cpu_s": 0.5, "simulated_s": 0.2,
                  "step": H}, {"e_ef_mm": 1.0, "tau_ef_Nm": 0.03}, None)]
    lines = tools.summary(results).splitlines()
    fmpy = next(line for line in lines if line.startswith("| default | fmpy |"))
    assert fmpy == "| default | fmpy | 0.8000-1.1000 | 1.0000-1.0500 | 2/2 | 2 | 0.2 | 1500-2500 (2000) |"
    libcosim = next(line for line in lines if line.startswith("| default | libcosim |"))
    assert libcosim == "| default | libcosim | – | – | 0/1 | – | – | – |"
    assert math.isnan(tools._ratio(1.0, 0.0)) and math.isnan(tools._ratio(None, 1.0))


def test_the_stored_runs_come_back_by_kind_then_scene_each_with_its_tools_in_the_order_asked():
    """stored_rows on runs stored in a scrambled order: the (kind, scene) groups in the order of
    KINDS, then TABLE_SCENES (a kind or scene outside them last); each group's rows in the order
    of the tools asked, each with its own metrics and our master's on that scene; our runs, the
    trials, a tool not asked and a scene without our run left out.  Catches the order of the
    kinds or scenes reversed or ignored, a row given another scene's master run, a tool not
    asked shown."""
    def run(value):
        return {"metrics": {"e_ef_mm": value}, "error": None}

    scenes = ("bench_triangle_TCMDx", "thesis_sim_circle", "bench_circle_PDq")
    stored = {tools._key("ours", s, "parcosim"): {"e_ef_mm": float(i)} for i, s in enumerate(scenes)}
    stored[tools._key("ours", "my_scene", "parcosim")] = {"e_ef_mm": 9.0}
    stored[tools._key("trial", "bench_circle_PDq", "per-component")] = {"substeps": 4}
    for i, (kind, scene, tool) in enumerate((
            ("per-component", "bench_triangle_TCMDx", "libcosim"), ("my_kind", "thesis_sim_circle", "fmpy"),
            ("default", "my_scene", "fmpy"), ("per-component", "bench_triangle_TCMDx", "fmpy"),
            ("default", "bench_circle_PDq", "ecos"), ("default", "thesis_sim_circle", "fmpy"),
            ("default", "bench_circle_PDq", "fmpy"), ("internal-observer", "no_master_run", "fmpy"),
            ("per-component", "thesis_sim_circle", "libcosim"))):
        stored[tools._key(kind, scene, tool)] = run(10.0 + i)
    found = tools.stored_rows(stored, ["fmpy", "ecos"])
    assert list(found) == [("default", "thesis_sim_circle"), ("default", "bench_circle_PDq"), ("default", "my_scene"),
                           ("per-component", "bench_triangle_TCMDx"), ("my_kind", "thesis_sim_circle")]
    assert [(t, m["e_ef_mm"], o["e_ef_mm"], e) for t, m, o, e in found[("default", "bench_circle_PDq")]] == [
        ("fmpy", 16.0, 2.0, None), ("ecos", 14.0, 2.0, None)]
    assert [(t, m["e_ef_mm"], o["e_ef_mm"]) for t, m, o, _ in found[("per-component", "bench_triangle_TCMDx")]] == [
        ("fmpy", 13.0, 0.0)]
    assert [(t, o["e_ef_mm"]) for t, _, o, _ in found[("default", "my_scene")]] == [("fmpy", 9.0)]
    everything = tools.stored_rows(stored)
    assert [t for t, *_ in everything[("per-component", "bench_triangle_TCMDx")]] == ["fmpy", "libcosim"]
    assert ("per-component", "thesis_sim_circle") in everything
    assert ("internal-observer", "no_master_run") not in everything


def test_a_results_file_in_folders_not_made_yet_is_written_with_them(tmp_path):
    """``_store`` into a/b/tools.json, neither folder existing: the run is stored and reads back.
    Catches the folder made without its parents (a FileNotFoundError; sibling of seed 4201
    [196])."""
    results = tmp_path / "a" / "b" / "tools.json"
    tools._store(results, tools._key("ours", "bench_circle_TCMDx", "parcosim"), {"e_ef_mm": 0.5})
    assert tools.load_results(results)[tools._key("ours", "bench_circle_TCMDx", "parcosim")]["e_ef_mm"] == 0.5
