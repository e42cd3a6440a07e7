"""scenarios/batch/report.py's files without its 16 runs (``run_bench`` replaced by made-up
metrics): report.png's bars read back from the axes against the metrics and the thesis' table,
metrics.json read back (a stopped run's NaN as null), report.md's numbers from the same metrics,
and ``run_bench``'s tasks (issue 31: the scenarios' weakest area; every written value read
back)."""
from __future__ import annotations

import json
import math

import matplotlib

from scenarios.batch import report
from scenarios.batch.report import KINDS, THESIS_BENCH, bench_scene_names
from tests.scenarios.batch.test_report import _metrics

matplotlib.use("Agg")


def _made_up(stopped=()):
    e_ef = {kind: {s: 0.5 + 0.25 * k + (1.0 if kind == "triangle" else 0.0) for k, s in enumerate(THESIS_BENCH[kind])}
            for kind in KINDS}
    return _metrics(e_ef, stopped)


def test_the_bars_are_ours_and_the_thesis_for_each_strategy_and_trajectory(tmp_path, monkeypatch):
    """Catches a bar of another scene, the thesis' e_ef and tau_ef columns swapped, the
    trajectories' panels swapped, and ours and the thesis' bars swapped."""
    import matplotlib.pyplot as plt

    kept, close = [], plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    metrics = _made_up()
    assert report.plot_report(metrics, tmp_path / "report.png") == tmp_path / "report.png"
    axes = kept[0].axes
    for col, kind in enumerate(KINDS):
        strategies = list(THESIS_BENCH[kind])
        for row, (key, index) in enumerate((("e_ef_mm", 0), ("tau_ef_Nm", 1))):
            ax = axes[2 * row + col]
            bars = [p.get_height() for p in ax.patches]
            assert bars == [metrics[f"bench_{kind}_{s}"][key] for s in strategies] + \
                [THESIS_BENCH[kind][s][index] for s in strategies], (kind, key)
            assert [t.get_text() for t in ax.get_xticklabels()] == strategies


def test_write_report_writes_the_metrics_the_figure_and_the_rendered_report(tmp_path, monkeypatch):
    """A stopped run among the 16: metrics.json holds each value read back exactly and null for
    its NaN; report.md is ``render`` of those metrics with the figure linked.  Catches a
    metric lost or changed on the way to the file, and the mode, progress, scheduler or
    workers not passed on (or passed as another); the folder made without its missing parent
    (sibling of seed 4201 [196])."""
    metrics = _made_up(stopped=("bench_triangle_PDx",))
    asked = []
    monkeypatch.setattr(report, "run_bench", lambda out, **kw: asked.append((out, kw)) or metrics)
    out = tmp_path / "new" / "r"
    path = report.write_report(out, mode="compiled", progress=print, scheduler="tcp://s:1", workers=3)
    assert asked == [(out, {"mode": "compiled", "progress": print, "scheduler": "tcp://s:1", "workers": 3})]
    back = json.loads((tmp_path / "new" / "r" / "metrics.json").read_text())
    assert list(back) == bench_scene_names()
    for name, values in metrics.items():
        for key, value in values.items():
            if isinstance(value, float) and math.isnan(value):
                assert back[name][key] is None, (name, key)
            else:
                assert back[name][key] == (list(value) if isinstance(value, tuple) else value), (name, key)
    assert path.read_text() == report.render(metrics, "compiled") + "\n![e_ef and τ_ef, ours and the thesis'](report.png)\n"
    # laid out as `parcosim run`'s metrics.json (indented, NaN as null, a final newline): one form for both
    from scenarios.run.runner import write_json

    same = write_json(tmp_path / "run_metrics.json", metrics)
    assert (tmp_path / "new" / "r" / "metrics.json").read_text() == same.read_text()
    assert (tmp_path / "new" / "r" / "report.png").stat().st_size > 0


def test_run_bench_runs_each_scene_as_a_task_into_its_own_folder(tmp_path, monkeypatch):
    """Catches a scene's folder shared, the stop time or mode not given to the tasks, plots
    off, the results not in the scenes' order, and the cluster options (client, scheduler,
    workers, processes, progress) not reaching the engine as given."""
    from scenarios.batch import engine

    seen = {}

    def run_tasks(tasks, **kwargs):
        seen["tasks"], seen["kwargs"] = tasks, kwargs
        return {t.key: {"scene": t.key} for t in reversed(tasks)}

    monkeypatch.setattr(engine, "run_tasks", run_tasks)
    names = ["bench_circle_TCx", "bench_triangle_PDq"]
    client, progress = object(), object()
    out = report.run_bench(tmp_path, mode="compiled", scenes=names, stop_time=0.5, workers=3, processes=False,
                           client=client, scheduler="tcp://host:8786", progress=progress)
    assert list(out) == names and out == {n: {"scene": n} for n in names}
    tasks = seen["tasks"]
    assert [t.key for t in tasks] == names and [t.out_dir for t in tasks] == [str(tmp_path / n) for n in names]
    assert all(t.mode == "compiled" and t.plots is True and t.scene.system.stop_time == 0.5 for t in tasks)
    assert seen["kwargs"] == {"client": client, "scheduler": "tcp://host:8786", "workers": 3,
                              "progress": progress, "processes": False}
