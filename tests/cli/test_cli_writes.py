"""``parcosim run`` writes its files safely (issue 13): ``--out`` checked before the run,
atomic files, write errors naming the file, SIGINT writes what was recorded and exits 130."""
from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import scenarios.run.runner as run_module
from fmus.status import RunStatus
from parcosim.cli import EXIT_INTERRUPTED, main
from tests.support.paths import ROOT

SCENE = "bench_circle_TCMDx"


@pytest.fixture
def short_runs(monkeypatch):
    """``parcosim run`` simulates 50 ms of the scene (the files are what is tested)."""
    original = run_module.simulate

    def simulate(system, **kwargs):
        return original(replace(system, stop_time=0.05), **kwargs)

    monkeypatch.setattr(run_module, "simulate", simulate)


def test_an_unwritable_out_is_reported_before_the_run(tmp_path, monkeypatch, capsys):
    """Catches an unwritable --out found only after the whole run, or reported in more than one line."""
    def never(*args, **kwargs):
        raise AssertionError("the run started")

    monkeypatch.setattr(run_module, "simulate", never)
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["run", SCENE, "--out", str(blocker / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(blocker / "out") in err[0] and "not writable" in err[0], err


def test_the_files_are_written_whole(tmp_path, short_runs, capsys):
    """Catches torn rows or a temporary file left in the output folder after a normal run."""
    assert main(["run", SCENE, "--out", str(tmp_path)]) == 0
    rows = (tmp_path / "result.csv").read_text().splitlines()
    assert len(rows) == 52 and len({row.count(",") for row in rows}) == 1
    assert json.loads((tmp_path / "metrics.json").read_text())["completed"] is True
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]       # no temporary left


def test_a_full_disk_names_the_file_and_keeps_the_previous_one(tmp_path, short_runs, monkeypatch, capsys):
    """Catches a write error on a full disk that truncates the previous result.csv, leaves a temporary, or
    does not name the file."""
    (tmp_path / "result.csv").write_text("previous\n")

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np, "savetxt", full)
    assert main(["run", SCENE, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(tmp_path / "result.csv") in err[0] and "No space left" in err[0], err
    assert (tmp_path / "result.csv").read_text() == "previous\n"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_a_failed_metrics_write_names_metrics_json(tmp_path, short_runs, monkeypatch, capsys):
    """Catches a failed metrics.json write reported under another file's name or as a success."""
    real = run_module.atomic_write

    def failing(path, write):
        if Path(path).name == "metrics.json":
            raise run_module.WriteError(errno.ENOSPC, f"cannot write {path}: No space left on device")
        return real(path, write)

    monkeypatch.setattr(run_module, "atomic_write", failing)
    assert main(["run", SCENE, "--out", str(tmp_path)]) == 2
    assert "metrics.json" in capsys.readouterr().err


def test_the_master_returns_the_rows_so_far_on_keyboard_interrupt(monkeypatch):
    """Catches Ctrl-C losing the rows recorded so far, a half-written row, or an interruption not recorded
    as its own kind with its time."""
    from fmus.cosim import stepper as stepper_module
    from fmus.cosim.master import simulate
    from scenarios.scenes.catalogue import get_scene

    calls = {"n": 0}
    step = stepper_module.Stepper.step

    def interrupted(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 20:
            raise KeyboardInterrupt
        return step(self, *args, **kwargs)

    monkeypatch.setattr(stepper_module.Stepper, "step", interrupted)
    result = simulate(replace(get_scene(SCENE).system, stop_time=0.1))
    assert result.interrupted and not result.completed
    assert str(result.error) == "interrupted at t = 0.019 s" and result.error.kind is RunStatus.INTERRUPTED
    assert result.status is RunStatus.INTERRUPTED and result.error.time == pytest.approx(0.019, abs=1e-12)
    assert len(result.time) == 20 and np.isfinite(result["plant.x"]).all()


#: Runs ``parcosim run`` with every communication step slowed by 2 ms (so that a SIGINT
#: lands mid-run) and prints "stepping" at the first step.
SLOW_RUN = textwrap.dedent("""
    import sys, time
    from fmus import stepper
    step = stepper.Stepper.step
    def slow(self, *args, **kwargs):
        if self.time == 0.0:
            print("stepping", flush=True)
        time.sleep(0.002)
        return step(self, *args, **kwargs)
    stepper.Stepper.step = slow
    from parcosim.cli import main
    sys.exit(main(sys.argv[1:]))
""")


@pytest.mark.parametrize("mode", ["inprocess", "fmu"])
def test_sigint_during_a_run_writes_what_was_recorded_and_exits_130(mode, tmp_path, built_fmus):
    """Catches SIGINT in a real process ending in a traceback, another exit status, torn files, or
    metrics.json without the interruption's record."""
    out = tmp_path / "out"
    args = ["run", SCENE, "--mode", mode, "--out", str(out)]
    if mode == "fmu":
        args += ["--fmu-dir", str(next(iter(built_fmus.values())).parent)]
    process = subprocess.Popen([sys.executable, "-c", SLOW_RUN, *args], cwd=ROOT, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        assert process.stdout.readline().strip() == "stepping"
        time.sleep(0.5)
        process.send_signal(signal.SIGINT)
        stdout, stderr = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == EXIT_INTERRUPTED, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and "interrupted at t = " in lines[0] and str(out) in lines[0], lines
    rows = (out / "result.csv").read_text().splitlines()
    assert len(rows) > 10 and len({row.count(",") for row in rows}) == 1       # whole rows
    data = np.loadtxt(out / "result.csv", delimiter=",", skiprows=1)
    assert np.isfinite(data).all()
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["completed"] is False and metrics["interrupted"] is True
    assert metrics["outcome"] == "interrupted" and metrics["error"]["kind"] == "interrupted"
    assert metrics["error"]["message"].startswith("interrupted at t = ") and metrics["error"]["message"] in lines[0]


#: ``parcosim run`` that prints "instantiating" and waits 1 s before the master loads the FMUs.
SLOW_START = textwrap.dedent("""
    import sys, time
    from fmus import master
    instantiate = master._instantiate
    def slow(*args, **kwargs):
        print("instantiating", flush=True)
        time.sleep(1.0)
        return instantiate(*args, **kwargs)
    master._instantiate = slow
    from parcosim.cli import main
    sys.exit(main(sys.argv[1:]))
""")


def test_sigint_during_fmu_initialisation_stops_after_it_cleanly(tmp_path, built_fmus):
    """The master defers the SIGINT: no KeyboardInterrupt inside an FMU's call (it crashed
    fmpy's process in 4 of 7 runs); the run stops before its first step with the row of t = 0."""
    out = tmp_path / "out"
    args = ["run", SCENE, "--mode", "fmu", "--out", str(out), "--fmu-dir",
            str(next(iter(built_fmus.values())).parent)]
    process = subprocess.Popen([sys.executable, "-c", SLOW_START, *args], cwd=ROOT, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        assert process.stdout.readline().strip() == "instantiating"
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == EXIT_INTERRUPTED, stderr
    assert "interrupted at t = 0 s" in stderr
    assert len((out / "result.csv").read_text().splitlines()) == 2          # header and t = 0
    assert json.loads((out / "metrics.json").read_text())["completed"] is False
