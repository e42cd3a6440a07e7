"""scenarios/studies/tools.py's ``compare`` with the export, the tools and our master replaced by
recorders (the real runs are of the slow kind, test_tools.py), and ``run_tool_isolated``'s
child that cannot run its tool: every option reaching what it chooses, each tool's row, a
tool's failure as a row (issue 31: options taking effect, error messages word for word)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from fmus.ssp.run import SspRun
from fmus.status import RunError, RunStatus
from scenarios.scenes import get_scene
from scenarios.studies import tools

SCENE = tools.short(get_scene("bench_circle_TCMDx"), 0.02)
COLUMNS = {"plant.x": "x", "plant.y": "y", "traj.x_d": "x_d", "traj.y_d": "y_d", "ctrl.tau1": "tau1",
           "ctrl.tau2": "tau2"}


def _run(tool: str, step: float, error=None) -> SspRun:
    """A tool's run over the scene at ``step``: x lags x_d by 1 mm (fmpy), 2 mm (ecos)."""
    t = np.arange(int(round(SCENE.system.stop_time / step)) + 1) * step
    lag = {"fmpy": 1e-3, "ecos": 2e-3}.get(tool, 0.0)
    signals = {"plant.x": np.full(t.size, -lag), "plant.y": np.zeros(t.size), "traj.x_d": np.zeros(t.size),
               "traj.y_d": np.zeros(t.size), "ctrl.tau1": np.full(t.size, 0.5), "ctrl.tau2": np.zeros(t.size)}
    return SspRun(t, signals, tool, wall_s=0.25, error=error, extra={"cpu_s": 0.125} if tool == "fmpy" else {})


@pytest.fixture
def recorded(monkeypatch, tmp_path):
    """export_kind, run_tool, run_tool_isolated and run_scene replaced; what each was given."""
    calls = {"export": [], "runs": [], "ours": []}

    def export_kind(kind, scene, directory, c_drive=None, substeps=None):
        calls["export"].append((kind, scene.name, Path(directory), c_drive, substeps))
        return tools.Exported(Path(directory) / "pkg.ssp", 5e-4, COLUMNS, foreign=kind.endswith("c-drive"))

    def runner(name):
        def run(tool, path, signals, stop_time, step, bindings=False):
            calls["runs"].append((name, tool, path.name, list(signals), stop_time, step, bindings))
            if tool == "libcosim":
                raise OSError("libcosimc.so: cannot open shared object file")
            refused = RunError(RunStatus.REFUSED, "ecos: plant refused", instance="plant", time=0.01)
            return _run(tool, step, refused if tool == "ecos" else None)
        return run

    class Outcome:
        metrics = {"e_ef_mm": 0.75, "tau_ef_Nm": 0.5}

    monkeypatch.setattr(tools, "export_kind", export_kind)
    monkeypatch.setattr(tools, "run_tool", runner("in process"))
    monkeypatch.setattr(tools, "run_tool_isolated", runner("isolated"))
    monkeypatch.setattr(tools, "run_scene", lambda scene, mode: calls["ours"].append((scene.name, mode)) or Outcome)
    return calls


def test_each_tool_runs_the_exported_package_and_gets_its_own_row(recorded, tmp_path):
    """Every tool in the order given, isolated by default, on the package with its columns, the
    scene's stop time and the package's step; fmpy gets the bindings only for a foreign FMU; a
    tool that cannot start is a FAILED row naming the exception; a tool's refusal is its row's
    error; each row's metrics are those of its run at the scene's step, with its CPU time (NaN
    when not measured) and the package's step; our master run once, in process.  Catches an
    option not passed on (kind, sub-steps, C drive, folder), rows in another order or another
    tool's run, the bindings given to every tool, a failure that ends the comparison."""
    rows = tools.compare(SCENE, ("fmpy", "libcosim", "ecos"), out_dir=tmp_path, kind="per-component+c-drive",
                         c_drive="drive.fmu", substeps=4)
    assert recorded["export"] == [("per-component+c-drive", SCENE.name, tmp_path, "drive.fmu", 4)]
    assert recorded["ours"] == [(SCENE.name, "inprocess")]
    signals = list(COLUMNS)
    assert recorded["runs"] == [("isolated", t, "pkg.ssp", signals, 0.02, 5e-4, t == "fmpy")
                                for t in ("fmpy", "libcosim", "ecos")]
    assert [(t, e) for t, _, _, e in rows] == [
        ("fmpy", None),
        ("libcosim", RunError(RunStatus.FAILED, "OSError: libcosimc.so: cannot open shared object file")),
        ("ecos", RunError(RunStatus.REFUSED, "ecos: plant refused", instance="plant", time=0.01))]
    (_, fmpy, ours, _), (_, failed, _, _), (_, ecos, _, _) = rows
    assert ours == {"e_ef_mm": 0.75, "tau_ef_Nm": 0.5} and failed is None
    for m, expected, lag in ((fmpy, tools.tool_metrics(SCENE, _run("fmpy", 5e-4), COLUMNS), 1.0),
                             (ecos, tools.tool_metrics(SCENE, _run("ecos", 5e-4), COLUMNS), 2.0)):
        assert m["e_ef_mm"] == pytest.approx(lag, rel=1e-12) == expected["e_ef_mm"]
        assert m["tau_ef_Nm"] == pytest.approx(0.5, rel=1e-12) and m["step"] == 5e-4
    assert fmpy["completed"] is True and ecos["completed"] is False
    assert fmpy["cpu_s"] == 0.125 and np.isnan(ecos["cpu_s"])


def test_in_process_our_given_run_and_a_plain_kind(recorded):
    """``isolated=False`` runs the tools in this process; ``ours`` given, our master is not run;
    a kind without a foreign FMU gives fmpy no bindings; without a folder the package goes to a
    temporary one.  Catches the flag ignored, our run repeated, the bindings given regardless."""
    rows = tools.compare(SCENE, ("ecos", "fmpy"), isolated=False, ours={"e_ef_mm": 2.0})
    assert recorded["ours"] == []
    assert [(r[0], r[1], r[6]) for r in recorded["runs"]] == [("in process", "ecos", False),
                                                             ("in process", "fmpy", False)]
    (kind, _, folder, c_drive, substeps), = recorded["export"]
    assert (kind, c_drive, substeps) == ("default", None, None) and folder.name.startswith("parcosim_pkg_")
    assert not folder.exists() and [r[2] for r in rows] == [{"e_ef_mm": 2.0}] * 2


def test_a_child_that_cannot_run_its_tool_is_a_runtime_error_with_its_last_words(tmp_path):
    """The isolated run of a tool the child does not know: the child's status and the last lines
    it wrote (the refusal naming the valid tools), word for word.  Catches the child's failure
    taken as a run (or its stdout read for its stderr), the tool's name or the package lost."""
    package = tmp_path / "none.ssp"
    with pytest.raises(RuntimeError) as refusal:
        tools.run_tool_isolated("openmodelica", package, ["plant.x"], 0.01, 1e-3)
    message = str(refusal.value)
    assert message.startswith(f"openmodelica run of {package} ended with status 1: ")
    assert message.endswith(f"ValueError: tool = 'openmodelica'; valid: {', '.join(tools.TOOLS)}")


def test_an_isolated_run_hands_its_arguments_to_the_child_exactly_and_counts_user_plus_system_cpu(
        tmp_path, monkeypatch):
    """The child (here run in process, its ``--child`` command line as given to the process)
    gets the tool, the package, stop time and step that read back to the same floats, the
    bindings flag and the signals in order; its run comes back with ``cpu_s`` the children's
    user time plus system time between the two readings.  Catches a float rounded on the
    command line, the flag inverted, a signal dropped, system time subtracted or left out."""
    given = []
    monkeypatch.setattr(tools, "run_tool", lambda tool, path, signals, stop, step, bindings: given.append(
        (tool, path, signals, stop, step, bindings)) or SspRun(np.zeros(1), {}, tool, 0.5))

    def run(argv, **kw):
        assert argv[:3] == [sys.executable, "-m", "scenarios.studies.tools"]
        assert tools.main(argv[3:]) == 0
        return subprocess.CompletedProcess(argv, 0, "", "")

    monkeypatch.setattr(tools.subprocess, "run", run)
    monkeypatch.setattr(tools.resource, "getrusage", lambda who: next(readings))
    stop, step = 0.1 + 0.2, 1 / 3 * 1e-3
    for bindings in (True, False):
        readings = iter([SimpleNamespace(ru_utime=10.0, ru_stime=4.0), SimpleNamespace(ru_utime=12.5, ru_stime=4.75)])
        out = tools.run_tool_isolated("ecos", tmp_path / "p.ssp", ["plant.x", "drive1.i", "ctrl.tau1"], stop, step,
                                      bindings=bindings)
        assert out.extra["cpu_s"] == 3.25 and out.tool == "ecos"
        assert given[-1] == ("ecos", str(tmp_path / "p.ssp"), ["plant.x", "drive1.i", "ctrl.tau1"], stop, step,
                             bindings)


def test_run_tool_hands_each_tool_its_arguments_and_keeps_fmpys_rows_up_to_the_stop(tmp_path, monkeypatch):
    """run_tool with the tools' own runners replaced by recorders: plain fmpy's rows relabelled
    to the end of their step (t + step) and cut after the stop time (fmpy may take a step more),
    only the signals asked for; fmpy with bindings run by simulate_ssp_fmpy without initial
    outputs, its refusal returned as it is; Ecos and libcosim given the package, the signals,
    stop time and step.  Catches the relabelling dropped or reversed, the last row kept or an
    in-time row cut, a signal of another name, an argument of one tool given to another."""
    import fmpy.ssp.simulation
    import fmus.ssp.libcosim
    import fmus.ssp.run

    step, stop = 1e-3, 3e-3
    table = np.zeros(4, dtype=[("time", float), ("plant.x", float), ("plant.y", float)])
    table["time"] = np.arange(4) * step                   # fmpy's times: the start of each step
    table["plant.x"], table["plant.y"] = [1.0, 2.0, 3.0, 4.0], [5.0, 6.0, 7.0, 8.0]
    seen = []
    monkeypatch.setattr(fmpy.ssp.simulation, "simulate_ssp",
                        lambda path, stop_time, step_size: seen.append((path, stop_time, step_size)) or table)
    run = tools.run_tool("fmpy", tmp_path / "p.ssp", ["plant.y"], stop, step)
    assert seen == [(str(tmp_path / "p.ssp"), stop, step)]
    assert run.tool == "fmpy" and run.error is None and list(run.signals) == ["plant.y"]
    assert run.time.tolist() == pytest.approx([1e-3, 2e-3, 3e-3], abs=1e-15)
    assert run.signals["plant.y"].tolist() == [5.0, 6.0, 7.0]

    bound = SspRun(np.array([0.0, 1e-3, 2e-3, 3e-3, 4e-3]), {"plant.x": np.arange(5.0), "plant.y": -np.arange(5.0)},
                   "fmpy", 0.25)
    refused = SspRun(np.zeros(0), {}, "fmpy", 0.5,
                     error=RunError(RunStatus.REFUSED, "plant: q1 absurd", instance="plant"))
    calls = []
    for given in (bound, refused):
        monkeypatch.setattr(fmus.ssp.run, "simulate_ssp_fmpy", lambda path, stop_time, step_size, initial_outputs:
                            calls.append((path, stop_time, step_size, initial_outputs)) or given)
        run = tools.run_tool("fmpy", tmp_path / "b.ssp", ["plant.x"], stop, step, bindings=True)
        if given is refused:
            assert run is refused
        else:
            assert run.time.tolist() == [0.0, 1e-3, 2e-3, 3e-3] and run.signals["plant.x"].tolist() == [0, 1, 2, 3]
            assert list(run.signals) == ["plant.x"]
    assert calls == [(tmp_path / "b.ssp", stop, step, False)] * 2

    for tool, module, name in (("ecos", fmus.ssp.run, "simulate_ssp_ecos"),
                               ("libcosim", fmus.ssp.libcosim, "simulate_ssp_libcosim")):
        got = []
        monkeypatch.setattr(module, name, lambda path, signals, stop_time, step_size: got.append(
            (path, signals, stop_time, step_size)) or bound)
        assert tools.run_tool(tool, tmp_path / "e.ssp", ("plant.x", "plant.y"), stop, step) is bound
        assert got == [(tmp_path / "e.ssp", ["plant.x", "plant.y"], stop, step)], tool
