"""scenarios/studies/robustness.py's tables from sweeps written here (nothing runs): the csv
files found under the study's folders read back exactly, and robustness.md's rows, ranking and
median changes against the numbers computed here (issue 31: written values read back and
compared; the scenarios' weakest area)."""
from __future__ import annotations

import math

import numpy as np

from scenarios.batch import sweep
from scenarios.scenes import get_scene
from scenarios.scenes.perturb import perturbable
from scenarios.studies import robustness


def _rows(e_ef, tau, failed=()):
    return [{"sample": k, "e_ef_mm": e, "tau_ef_Nm": t, "e_ss_mm": 0.01 * e, "e_ss_1s_mm": 0.0, "t_settle_s": 1.0,
             "completed": k not in failed, "error": "x" if k in failed else "", "wall_s": 1.0}
            for k, (e, t) in enumerate(zip(e_ef, tau))]


def _found():
    """circle at U = 0.2: PDq and PDMDq (a pair), TCx alone; their nominal runs."""
    return {("circle", "PDq", 0.0): _rows([0.40], [0.020]),
            ("circle", "PDq", 0.2): _rows([0.5, 0.7, 0.6, 9.9, 0.9], [0.02, 0.03, 0.025, 0.5, 0.035], failed=(3,)),
            ("circle", "PDMDq", 0.2): _rows([0.30, 0.45, 0.35, 0.40, 0.50], [0.021, 0.022, 0.023, 0.024, 0.025]),
            ("circle", "TCx", 0.2): _rows([0.2, 0.8, math.nan, 0.3, 0.25], [0.01] * 5)}


def test_a_strategys_row_is_its_nominal_and_the_percentiles_of_its_completed_samples():
    """Catches a failed sample counted (PDq's 9.9 mm), the nominal taken from the perturbed
    run, the 5 and 95 % quantiles swapped, median / nominal inverted, the failed count."""
    text = robustness.render(_found(), uncertainties=(0.2,), command="python -m scenarios.studies.robustness")
    lines = text.splitlines()
    assert lines[:4] == ["# Robustness of the eight strategies (sweeps)", "",
                         "`python -m scenarios.studies.robustness`", ""]
    assert "## circle, U = 0.2 (5 samples per strategy)" in lines
    assert not any(line.startswith("## triangle") or "U = 0.1" in line for line in lines)
    e = [0.5, 0.7, 0.6, 0.9]
    tau = [0.02, 0.03, 0.025, 0.035]
    median = float(np.median(e))
    expected = (f"| PDq | 0.400 | {median:.3f} | {np.percentile(e, 5):.3f}-{np.percentile(e, 95):.3f} | "
                f"{median / 0.4:.2f} | 0.0200 | {np.median(tau):.4f} | {np.percentile(tau, 95):.4f} | "
                f"{np.median([0.01 * x for x in e]):.3f} | 1 |")
    assert expected in lines
    tcx = next(line for line in lines if line.startswith("| TCx |"))
    assert tcx.startswith("| TCx | nan | 0.275 |") and tcx.endswith("| 0 |")      # no nominal run found


def test_the_reading_ranks_by_the_95_percent_quantile_and_gives_each_pairs_median_change():
    """Catches the robustness reading ranking by the mean or median instead of the 95 % quantile, or
    computing the sliding-mode term's change from the wrong medians."""
    lines = robustness.render(_found(), uncertainties=(0.2,)).splitlines()
    p95 = {"PDq": np.percentile([0.5, 0.7, 0.6, 0.9], 95), "PDMDq": np.percentile([0.30, 0.45, 0.35, 0.40, 0.50], 95),
           "TCx": np.percentile([0.2, 0.8, 0.3, 0.25], 95)}
    ranked = sorted(p95, key=p95.get)
    assert f"Ranking by the 95 % quantile of e_ef, best first: {', '.join(ranked)}." in lines
    change = 100 * (0.40 - 0.65) / 0.65
    assert f"Median e_ef change from adding the sliding-mode term: PDq→PDMDq {change:+.0f} %." in lines


def test_the_study_reads_back_the_sweeps_it_finds_under_its_folders(tmp_path):
    """Each (scene, U) at OUT/<scene>/U<U>/sweep.csv with the scene's own header; U = 0 the
    nominal run; folders with no file are left out.  Catches the folder's name formatted
    another way (U0.2 vs U0.20), the header of another scene, a kind or U not looked for."""
    scene = "bench_triangle_TCMDx"
    header = sweep.columns([p.name for p in perturbable(get_scene(scene))])
    written = {}
    for U, folder in ((0.0, "U0"), (0.2, "U0.2")):
        rows = [{**{name: 0.5 + 0.1 * k for name in header}, "sample": k, "completed": True,
                 **sweep.error_columns({"outcome": "completed"}), "e_ef_mm": 0.1 * (k + 1) + U} for k in range(3)]
        path = tmp_path / scene / folder / "sweep.csv"
        path.parent.mkdir(parents=True)
        appender = sweep._Appender(path, header)
        for row in rows:
            appender.append(row)
        appender.close()
        written["triangle", "TCMDx", U] = rows
    found = robustness.load(tmp_path, kinds=("triangle",), uncertainties=(0.1, 0.2))
    assert repr(found) == repr(written)     # exact, a completed row's NaN error time and value included


def test_the_study_runs_the_nominal_runs_then_each_stage_of_every_sweep_in_its_folder(tmp_path, monkeypatch):
    """run_study with the sweeps and the cluster replaced: first one nominal run (U = 0) of
    every scene, then each stage below N and N itself, every U, every scene, each in
    ``<out>/<scene>/U<U>``.  Catches a stage at or above N run, a scene or U left out, a
    sweep written to another sweep's folder, and the cluster not shared."""
    import contextlib
    from types import SimpleNamespace

    calls, clients = [], []

    @contextlib.contextmanager
    def open_client(scheduler, workers):
        clients.append((scheduler, workers))
        yield "the client"

    def run_sweep(scene, n, U, mode, out_dir, client, plots):
        calls.append((scene, n, U, out_dir))
        assert client == "the client" and plots is False and mode == "compiled"
        return SimpleNamespace(computed=list(range(n)), summary={"failed": 0})

    monkeypatch.setattr(robustness, "open_client", open_client)
    monkeypatch.setattr(robustness, "run_sweep", run_sweep)
    said = []
    robustness.run_study(tmp_path, samples=8, stages=(2, 8, 4), uncertainties=(0.1, 0.4), kinds=("triangle",),
                         workers=3, mode="compiled", say=said.append)
    scenes = [f"bench_triangle_{s}" for s in robustness.STRATEGIES]
    nominal = [(s, 1, 0.0, tmp_path / s / "U0") for s in scenes]
    staged = [(s, n, U, tmp_path / s / f"U{U:g}") for n in (2, 4, 8) for U in (0.1, 0.4) for s in scenes]
    assert calls == nominal + staged and clients == [(None, 3)]
    assert said[0].startswith("bench_triangle_PDq U=0.1 N=2: 2 run in ") and said[0].endswith(" s, 0 failed")
    assert len(said) == len(staged)
