"""scenarios/batch/sweep.py's ``run_sweep``: every option reaches what it is documented to
change, with the cluster replaced by a made-up one (``run_tasks`` recording what it is given):
the cluster's settings and ``progress`` passed on, ``mode`` and ``stop_time`` in each task,
``on_row`` called with each row as it is recorded, the distribution taken from the argument,
else the perturb spec, else uniform, and the spec's uncertainties used, nothing written without
``out_dir`` and the summary and figure written with it (issue 31: CLI/API options actually
taking effect; the scenarios' weakest area)."""
from __future__ import annotations

import math

import pytest

from scenarios.batch import sweep as sweep_module
from scenarios.batch.sweep import run_sweep, summary_markdown
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.perturb import draw, perturbable, uncertainties

SCENE = "bench_circle_PDq"


def _metrics(i: int) -> dict:
    return {"completed": True, "outcome": "completed", "e_ef_mm": 1.0 + i, "tau_ef_Nm": 0.25 * i,
            "e_ss_mm": 0.5, "e_ss_1s_mm": 0.75, "t_settle_s": 1.5, "wall_s": 2.0, "error": None}


@pytest.fixture
def cluster(monkeypatch):
    """run_tasks replaced: records its tasks and keyword arguments, finishes the tasks last
    first and reports a progress fraction after each."""
    given = {}

    def run_tasks(tasks, on_result=None, progress=None, **kwargs):
        given.update(kwargs, tasks=list(tasks), progress=progress)
        for k, task in enumerate(reversed(tasks), start=1):
            on_result(task, _metrics(int(task.key.removeprefix("sample"))))
            if progress is not None:
                progress(k / len(tasks))
        return {}

    monkeypatch.setattr(sweep_module, "run_tasks", run_tasks)
    return given


def test_the_cluster_mode_stop_time_and_callbacks_reach_the_tasks(cluster):
    """Catches the client, scheduler, workers or processes not passed on, ``progress`` not the
    caller's, the mode or the stop time left out of a task, ``on_row`` not called or called
    without the row (or a row of another sample), and files written without ``out_dir``."""
    client, rows, fractions = object(), [], []
    sweep = run_sweep(SCENE, 3, 0.1, seed=5, mode="fmu", stop_time=0.5, client=client, scheduler="tcp://h:1",
                      workers=3, processes=False, progress=fractions.append, on_row=rows.append)
    assert cluster["client"] is client and cluster["scheduler"] == "tcp://h:1" and cluster["workers"] == 3
    assert cluster["processes"] is False and fractions == [1 / 3, 2 / 3, 1.0]
    tasks = cluster["tasks"]
    assert [t.key for t in tasks] == ["sample0", "sample1", "sample2"]
    assert {t.mode for t in tasks} == {"fmu"} and {t.scene.system.stop_time for t in tasks} == {0.5}
    assert sweep.settings["stop_time"] == 0.5 and sweep.settings["mode"] == "fmu"
    assert [r["sample"] for r in rows] == [2, 1, 0]
    assert [r["e_ef_mm"] for r in rows] == [3.0, 2.0, 1.0]
    assert all(row is sweep.rows[row["sample"]] for row in rows)
    assert sweep.files == []


def _values(sweep, distribution, overrides=None, seed=5, U=0.1):
    parameters = perturbable(get_scene(SCENE))
    spread = uncertainties(parameters, U, overrides)
    return [{p.name: r[p.name] for p in parameters} for r in sweep.rows] == \
        [draw(parameters, spread, seed, i, distribution) for i in range(len(sweep.rows))]


@pytest.mark.parametrize("argument, in_spec, used", [(None, None, "uniform"), (None, "normal", "normal"),
                                                     ("uniform", "normal", "uniform"), ("normal", None, "normal")])
def test_the_distribution_is_the_arguments_else_the_perturb_specs_else_uniform(cluster, argument, in_spec, used):
    """Catches the perturb spec's distribution overriding the argument (or ignored), a default
    other than uniform, and the draws not of the distribution the settings name."""
    spec = {"uncertainty": {}, "distribution": in_spec}
    sweep = run_sweep(SCENE, 2, 0.1, seed=5, distribution=argument, perturb=spec)
    assert sweep.settings["distribution"] == used and _values(sweep, used)
    assert not _values(sweep, {"uniform": "normal", "normal": "uniform"}[used])


def test_the_perturb_specs_uncertainties_override_the_weights_and_are_recorded(cluster):
    """Catches the spec's per-parameter uncertainties ignored or recorded as other values."""
    parameters = perturbable(get_scene(SCENE))
    name = next(p.name for p in parameters if not p.follows)
    spec = {"uncertainty": {name: 0.375}, "distribution": None}
    sweep = run_sweep(SCENE, 2, 0.1, seed=3, perturb=spec)
    assert sweep.settings["perturb"] == {name: 0.375} and sweep.settings["spread"][name] == 0.375
    assert _values(sweep, "uniform", {name: 0.375}, seed=3)


def test_an_unknown_distribution_is_refused_naming_the_valid_ones(cluster):
    """Catches a misspelt distribution run as the default."""
    with pytest.raises(ValueError, match=r"^distribution = 'gauss'; valid: uniform, normal$"):
        run_sweep(SCENE, 1, 0.1, distribution="gauss")
    assert "tasks" not in cluster


def test_with_out_dir_the_summary_and_figure_are_written_and_listed(cluster, tmp_path, monkeypatch):
    """summary.md is the sweep's own summary_markdown, sweep.png the plot's, each listed in
    ``files`` after sweep.json, sweep.csv and summary.json; ``plots=False`` writes no figure.
    Catches a file written under another name or not listed, and plots drawn when not asked."""
    drawn = []
    from scenarios.batch import sweep_plots

    monkeypatch.setattr(sweep_plots, "plot_sweep", lambda sweep, path: drawn.append(path) or path)
    sweep = run_sweep(SCENE, 2, 0.1, out_dir=tmp_path / "a")
    out = tmp_path / "a"
    assert sweep.files == [out / "sweep.json", out / "sweep.csv", out / "summary.json", out / "summary.md",
                           out / "sweep.png"]
    assert drawn == [out / "sweep.png"]
    assert (out / "summary.md").read_text() == summary_markdown(sweep)
    quiet = run_sweep(SCENE, 2, 0.1, out_dir=tmp_path / "b", plots=False)
    assert quiet.files[-1] == tmp_path / "b" / "summary.md" and drawn == [out / "sweep.png"]
    assert not math.isnan(quiet.summary["e_ef_mm"]["mean"])


def test_a_perturb_file_path_is_read_as_its_spec(cluster, tmp_path):
    """``perturb`` given as a TOML file's path (what ``--perturb FILE`` passes): its uncertainty and
    distribution are those of the file.  Catches the path not the one read (seed 4001 [258]:
    ``load_perturb_file(on_row)``)."""
    parameters = perturbable(get_scene(SCENE))
    name = next(p.name for p in parameters if not p.follows)
    path = tmp_path / "perturb.toml"
    path.write_text(f'distribution = "normal"\n[uncertainty]\n"{name}" = 0.375\n', encoding="utf-8")
    sweep = run_sweep(SCENE, 2, 0.1, seed=3, perturb=path)
    assert sweep.settings["perturb"] == {name: 0.375} and sweep.settings["distribution"] == "normal"
    assert _values(sweep, "normal", {name: 0.375}, seed=3)
