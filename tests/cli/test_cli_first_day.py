"""The first day with ``parcosim`` (issue 29): a refused command says one line, exits 2 and
leaves nothing behind; arguments are checked before any work; misspelled names get a
suggestion; every option has help; a sweep whose every sample failed exits 1 and its rows are
in sample order; a pendulum run reports and plots the pendulum; files follow the umask."""
from __future__ import annotations

import argparse
import json
import math
import os
import stat
import zipfile
from dataclasses import replace
from pathlib import Path

import pytest

import scenarios.run.runner as run_module
from fmus.status import RunStatus, RunError
from parcosim.cli import _parser, main
from scenarios.batch.sweep import read_rows

SCENE = "bench_circle_TCMDx"


def _tree(root: Path) -> set:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


@pytest.fixture
def short_runs(monkeypatch):
    """``parcosim run`` simulates 0.3 s of the scene (what is printed and written is tested)."""
    original = run_module.simulate

    def simulate(system, **kwargs):
        return original(replace(system, stop_time=0.3), **kwargs)

    monkeypatch.setattr(run_module, "simulate", simulate)


@pytest.fixture
def no_work(monkeypatch):
    """Any simulation, trade or export started fails the test: refusals come before work."""
    def never(*args, **kwargs):
        raise AssertionError("work started before the arguments were checked")

    import fmus.systemfmu.export
    import scenarios.studies.trade

    monkeypatch.setattr(run_module, "simulate", never)
    monkeypatch.setattr(scenarios.studies.trade, "run_trade", never)
    monkeypatch.setattr(fmus.systemfmu.export, "export_fmu", never)


REFUSED = {
    "misspelled command": (["rnu", SCENE], "did you mean 'run'?"),
    "misspelled scene": (["run", "bench_circle_TCMdx", "--out", "a/b"], "did you mean 'bench_circle_TCMDx'?"),
    "misspelled scene, export": (["export-fmu", "pendulum_balanse", "a/b.fmu"], "did you mean 'pendulum_balance'?"),
    "bad choice": (["run", SCENE, "--coupling", "jacob", "--out", "a/b"], "invalid choice: 'jacob'"),
    "retry 1": (["run", SCENE, "--retry-substeps", "1", "--out", "a/b"], "retry_substeps = 1 must be an integer >= 2"),
    "drives 0": (["run", SCENE, "--drives-in-plant", "0"], "--drives-in-plant = 0 must be an integer >= 1"),
    "not an fmu": (["run", SCENE, "--replace", "drive1=notanfmu.fmu", "--out", "a/b"], "notanfmu.fmu is not an FMU"),
    "missing fmu": (["run", SCENE, "--replace", "drive1=missing.fmu", "--out", "a/b"], "not an existing .fmu file"),
    "no samples": (["sweep", SCENE, "--samples", "0", "--uncertainty", "0.1", "--out", "a/b"],
                   "--samples = 0 must be an integer >= 1"),
    "negative U": (["sweep", SCENE, "--samples", "2", "--uncertainty", "-0.1", "--out", "a/b"], "--uncertainty"),
    "file for a folder": (["export-fmu", SCENE, "blocker/x.fmu"], "blocker is a file, not a folder"),
    "folder for a file": (["export-fmu", SCENE, "folder"], "folder is a folder; give the file to write"),
    "trade --out": (["trade", "--quick", "--out", "blocker/trade"], "blocker is a file, not a folder"),
    "bad circle": (["workspace", "bench", "--circle", "0,0.2", "--out", "w/x"], "write CX,CY,R in metres"),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_a_refused_command_says_one_line_exits_2_and_leaves_nothing(case, tmp_path, monkeypatch, capfd, no_work):
    """Catches a refused command that prints a traceback or several lines, writes to stdout, exits
    otherwise than 2, or leaves a file or folder behind."""
    argv, expected = REFUSED[case]
    monkeypatch.chdir(tmp_path)
    (tmp_path / "blocker").write_text("")
    (tmp_path / "folder").mkdir()
    (tmp_path / "notanfmu.fmu").write_text("not a zip")
    before = _tree(tmp_path)
    assert main(argv) == 2
    captured = capfd.readouterr()
    lines = (captured.out + captured.err).strip().splitlines()
    assert len(lines) == 1 and expected in lines[0], lines
    assert captured.out == ""
    assert _tree(tmp_path) == before


def test_a_refusal_after_the_output_folder_was_made_removes_it(tmp_path, monkeypatch, capfd):
    """The run makes its folder, then a component refuses to start: the empty folder goes,
    a folder that was there stays."""
    def refused(*args, **kwargs):
        raise ValueError("plant: m1 = -1 kg must be > 0")

    monkeypatch.setattr(run_module, "simulate", refused)
    monkeypatch.chdir(tmp_path)
    assert main(["run", SCENE, "--out", "new/deeper"]) == 2
    assert not (tmp_path / "new").exists()
    (tmp_path / "kept").mkdir()
    assert main(["run", SCENE, "--out", "kept"]) == 2
    assert (tmp_path / "kept").is_dir()
    lines = capfd.readouterr().err.strip().splitlines()
    assert lines == ["parcosim: error: plant: m1 = -1 kg must be > 0"] * 2


def _actions(parser: argparse.ArgumentParser, prefix: str = "parcosim"):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                yield from _actions(child, f"{prefix} {name}")
        elif not isinstance(action, argparse._HelpAction):
            yield prefix, action


def test_every_option_and_command_has_help():
    """Catches an option or command added without help text, or a top-level help that does not say what
    bare parcosim runs."""
    from motor.cli import _parser as identify_parser

    parser = _parser()
    actions = [*_actions(parser), *_actions(identify_parser(), "parcosim identify-motor")]
    missing = [f"{where} {action.option_strings or action.dest}" for where, action in actions
               if not (action.help and action.help.strip())]
    assert not missing, missing
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert {c.dest for c in commands._choices_actions} == set(commands.choices)      # each command has a help
    assert all(c.help for c in commands._choices_actions)
    assert f"Bare `parcosim` runs `parcosim run {SCENE}`" in parser.description


def test_a_pendulum_run_names_its_pitch_and_plots_the_pendulum(tmp_path, short_runs, capsys):
    """Catches a pendulum run that prints the 5R's e_ef as its result, or plots its tracking error instead
    of pitch, wheel speeds and voltages."""
    assert main(["run", "pendulum_balance", "--out", str(tmp_path)]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert "e_ef" not in last and "pitch peak" in last
    assert f"last second {metrics['last_second_pitch_deg']:.3g} deg" in last
    assert f"peak {metrics['peak_pitch_deg']:.3g} deg" in last
    assert metrics["peak_pitch_deg"] == pytest.approx(5.0, abs=0.5)     # released at 5 degrees
    for name in ("pitch.png", "wheel_speeds.png", "voltages.png", "path.png"):
        assert (tmp_path / name).stat().st_size > 1000, name
    assert not (tmp_path / "errors.png").exists()       # the 5R's tracking error means nothing here


@pytest.mark.parametrize("mask", [0o022, 0o007])
def test_written_files_follow_the_umask(mask, tmp_path, short_runs, capsys):
    """Catches result files and rewritten archives written 0600 (a temporary file's mode) instead of
    following the user's umask."""
    old = os.umask(mask)
    try:
        assert main(["run", SCENE, "--out", str(tmp_path / "run")]) == 0
        source = tmp_path / "a.zip"
        with zipfile.ZipFile(source, "w") as z:
            z.writestr("x", "1")
        from fmus.export.archive import rewrite

        copy = rewrite(source, tmp_path / "b.zip", {"y": "2"})
    finally:
        os.umask(old)
    for path in (tmp_path / "run" / "result.csv", tmp_path / "run" / "metrics.json", copy):
        assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~mask, path


def _fake_engine(failing: set):
    """run_tasks that finishes the samples in reverse order, the ``failing`` ones refused."""
    def run_tasks(tasks, on_result=None, progress=None, **kwargs):
        for task in reversed(tasks):
            i = int(task.key.removeprefix("sample"))
            ok = i not in failing
            error = None if ok else RunError(RunStatus.REFUSED, f"refused {i}", "plant", 0.5 + i, "q1", 2.0, "rad", 3,
                                             "BAD_INPUT")
            on_result(task, {"e_ef_mm": 1.0 + i, "tau_ef_Nm": 0.1, "e_ss_mm": 0.01, "e_ss_1s_mm": 0.01,
                             "t_settle_s": 0.5, "completed": ok, "outcome": (error.kind if error else RunStatus.COMPLETED).value,
                             "error": error and error.record(), "wall_s": 0.1})
        return {}
    return run_tasks


@pytest.mark.parametrize("failing, status", [(set(), 0), ({1, 3}, 0), ({0, 1, 2, 3}, 1)])
def test_a_sweep_exits_1_only_when_every_sample_failed_and_writes_rows_by_sample(
        failing, status, tmp_path, monkeypatch, capsys):
    import scenarios.batch.sweep

    monkeypatch.setattr(scenarios.batch.sweep, "run_tasks", _fake_engine(failing))
    assert main(["sweep", SCENE, "--samples", "4", "--uncertainty", "0.1", "--out", str(tmp_path)]) == status
    captured = capsys.readouterr()
    assert f"{4 - len(failing)} completed, {len(failing)} failed" in captured.out
    assert ("every sample failed; the first: refused" in captured.err) == (status == 1)
    lines = (tmp_path / "sweep.csv").read_text().splitlines()
    assert [int(line.split(",")[0]) for line in lines[1:]] == [0, 1, 2, 3]
    rows = read_rows(tmp_path / "sweep.csv", lines[0].split(","))
    for row in rows:       # the error's record as columns, read back with their types
        bad = row["sample"] in failing
        assert row["outcome"] == ("refused" if bad else "completed") and row["error"] == (f"refused {row['sample']}"
                                                                                          if bad else "")
        assert (row["error_instance"], row["error_variable"], row["error_unit"], row["error_code"]) == \
            (("plant", "q1", "rad", 3) if bad else ("", "", "", None))
        assert row["error_time"] == 0.5 + row["sample"] if bad else math.isnan(row["error_time"])


def test_the_workspace_figure_holds_the_whole_workspace(tmp_path):
    """Every point the 5R reaches in its working mode lies inside the drawn map, also below the
    bases (the figure was cropped at y = -0.1 m, leaving out a quarter of the bench's workspace
    and a branch of det J_X = 0)."""
    from plant import fivebar, get_preset
    from scenarios.studies.workspace import plot_workspace

    plot_workspace("bench", tmp_path, step=0.005)
    x0, x1, y0, y1 = json.loads((tmp_path / "workspace.json").read_text())["map_extent"]
    wide = fivebar.workspace_map(get_preset("bench"), step=0.005, extent=(-0.6, 0.6, -0.6, 0.6))
    iy, ix = (wide.status != fivebar.WorkspaceMap.OUTSIDE).nonzero()
    xs, ys = wide.x[ix], wide.y[iy]
    assert len(xs) > 1000 and (ys < -0.1).mean() > 0.2         # a quarter of it lies below y = -0.1 m
    assert xs.min() >= x0 and xs.max() <= x1 and ys.min() >= y0 and ys.max() <= y1


def test_a_retry_that_retried_nothing_says_so(tmp_path, short_runs, capsys):
    """--retry-substeps saves every state at every step: a run that needed no retry says the option
    only cost time (a user otherwise keeps paying for it)."""
    assert main(["run", "thesis_sim_circle", "--retry-substeps", "4", "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    assert "no step was refused, so --retry-substeps retried nothing" in err
    assert json.loads((tmp_path / "metrics.json").read_text())["retried_steps"] == []
