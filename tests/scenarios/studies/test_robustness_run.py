"""scenarios/studies/robustness.py's runs without running a sweep (run_sweep and the cluster
replaced by recorders): every option of the command reaching run_study, --render-only running
nothing, and run_study's order of sweeps (each scene's nominal run, then each stage, then the
sample count, each U, each scene) into OUT/<scene>/U<U> (issue 31: options taking effect; the
study's real runs are hours long)."""
from __future__ import annotations

import contextlib
from pathlib import Path
from types import SimpleNamespace

from scenarios.batch import sweep
from scenarios.scenes import get_scene
from scenarios.scenes.perturb import perturbable
from scenarios.studies import robustness


def test_the_commands_options_reach_run_study_and_render_only_runs_nothing(tmp_path, monkeypatch, capsys):
    """Catches an option not passed on (or passed as another), --render-only ignored or
    inverted (the study run instead of only the tables), the stages or U list misparsed."""
    calls = []

    def run_study(*a, **k):          # one sweep of one scene at the first U, for the tables
        calls.append((a, k))
        header = sweep.columns([p.name for p in perturbable(get_scene("bench_circle_PDq"))])
        path = Path(a[0]) / "bench_circle_PDq" / f"U{a[3][0]:g}" / "sweep.csv"
        path.parent.mkdir(parents=True, exist_ok=True)
        appender = sweep._Appender(path, header)
        appender.append({**{name: 0.5 for name in header}, "sample": 0, "completed": True,
                         **sweep.error_columns({"outcome": "completed"}), "e_ef_mm": 0.4, "tau_ef_Nm": 0.02,
                         "e_ss_mm": 0.01, "e_ss_1s_mm": 0.0, "t_settle_s": 1.0, "wall_s": 1.0})
        appender.close()

    monkeypatch.setattr(robustness, "run_study", run_study)
    out = tmp_path / "study"
    argv = ["--samples", "7", "--stages", "2,5", "--uncertainties", "0.05,0.3", "--workers", "3",
            "--mode", "compiled", "--scheduler", "tcp://127.0.0.1:8786", "--out", str(out)]
    assert robustness.main(argv) == 0
    assert len(calls) == 1
    (a, k), = calls
    assert a == (str(out), 7, (2, 5), (0.05, 0.3))
    assert {key: k[key] for key in ("workers", "scheduler", "mode")} == {
        "workers": 3, "scheduler": "tcp://127.0.0.1:8786", "mode": "compiled"}
    assert (out / "robustness.md").exists() and capsys.readouterr().out.strip() == str(out / "robustness.md")
    calls.clear()
    assert robustness.main(["--render-only", "--out", str(out), "--uncertainties", "0.05"]) == 0
    assert calls == []
    monkeypatch.chdir(tmp_path)
    assert robustness.main([]) == 0
    (a, k), = calls
    assert a == ("out/robustness", 100, (), robustness.UNCERTAINTIES)
    assert (k["workers"], k["scheduler"], k["mode"]) == (None, None, "inprocess")


def test_run_study_brings_every_sweep_to_each_stage_then_to_the_sample_count(tmp_path, monkeypatch):
    """Calls in order: each scene's nominal sweep (1 sample, U = 0) into OUT/<scene>/U0, then for
    each stage below the sample count and for the sample count, each U and each scene; all on
    the one client opened with the scheduler and workers given, in the mode given, no plots.
    Catches a stage at or above the sample count run, the sample count left out, scenes of one
    kind only, a sweep in another folder or mode, a cluster per sweep."""
    opened, runs, said = [], [], []

    @contextlib.contextmanager
    def open_client(scheduler, workers):
        opened.append((scheduler, workers))
        yield "the client"

    def run_sweep(scene, n, U, mode, out_dir, client, plots):
        runs.append((scene, n, U, mode, out_dir, client, plots))
        return SimpleNamespace(computed=[0] * n, summary={"failed": 0})

    monkeypatch.setattr(robustness, "open_client", open_client)
    monkeypatch.setattr(robustness, "run_sweep", run_sweep)
    robustness.run_study(tmp_path, samples=6, stages=(2, 6, 9, 4), uncertainties=(0.1, 0.25), workers=2,
                         scheduler="tcp://h:1", mode="compiled", say=said.append)
    assert opened == [("tcp://h:1", 2)]
    scenes = [f"bench_{k}_{s}" for k in ("circle", "triangle") for s in robustness.STRATEGIES]
    expected = [(s, 1, 0.0) for s in scenes] + [(s, n, U) for n in (2, 4, 6) for U in (0.1, 0.25) for s in scenes]
    assert [(s, n, U) for s, n, U, *_ in runs] == expected
    for s, n, U, mode, out_dir, client, plots in runs:
        assert out_dir == tmp_path / s / ("U0" if U == 0.0 else f"U{U:g}")
        assert (mode, client, plots) == ("compiled", "the client", False)
    assert len(said) == len(expected) - len(scenes)
    assert said[0].startswith(f"{scenes[0]} U=0.1 N=2: 2 run in ") and said[0].endswith(" s, 0 failed")
