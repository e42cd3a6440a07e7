"""Every ``parcosim`` command reaches the Python call its module docstring names
(parcosim/cli.py) with each of its options' values, given or default, and prints what the
call returned: the calls are replaced by recorders here, so no simulation, build or export
runs (issue 31: an option read into the wrong argument, dropped, or a default folder built
wrong, passed every test that only ran the commands with their defaults)."""
from __future__ import annotations

import importlib
import io
import zipfile
from pathlib import Path
from types import SimpleNamespace

import pytest

from fmus.export.build import DEFAULT_OUT
from fmus.native.build import DEFAULT_NATIVE_OUT
from parcosim.cli import DEFAULT_SCENE, main

SCENE = "bench_circle_TCMDx"


@pytest.fixture
def record(monkeypatch):
    """``record("module", "name", result)``: the function replaced by one that records each
    call's (args, kwargs) in the list it returns and returns ``result``."""
    def install(module: str, name: str, result=None):
        calls = []

        def recorder(*args, **kwargs):
            calls.append((args, kwargs))
            return result(*args, **kwargs) if callable(result) else result

        monkeypatch.setattr(importlib.import_module(module), name, recorder)
        return calls
    return install


@pytest.fixture
def fmu_file(tmp_path):
    """A file that passes for an FMU (a zip archive holding a modelDescription.xml)."""
    path = tmp_path / "supplier.fmu"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("modelDescription.xml", "<fmiModelDescription/>")
    return path


def _outcome(**metrics):
    base = {"mode": "inprocess", "e_ef_mm": 0.5, "tau_ef_Nm": 0.25, "e_ss_mm": 0.125, "wall_s": 2.0,
            "realtime_factor": 4.5, "settled": False, "retried_steps": 0}
    return SimpleNamespace(metrics={**base, **metrics}, result=SimpleNamespace(error=None, time=[]))


def _model(scene, instance: str) -> str:
    return next(c.model for c in scene.system.components if c.name == instance)


def test_run_passes_every_option_to_run_scene_and_prints_its_metrics(tmp_path, monkeypatch, record, fmu_file,
                                                                      capsys):
    """``run`` with every option given: ``run_scene`` gets the scene with its drives in the
    plant (RK4 N steps) and the replaced instance's FMU file, the mode, the folder, the
    coupling, the FMU folder and the retries; the line printed carries the metrics and the
    folder.  Catches an option not passed on, passed as another, or the scene's transforms
    dropped."""
    monkeypatch.chdir(tmp_path)
    calls = record("scenarios.run.runner", "run_scene", _outcome(mode="fmu", retried_steps=2, compile_s=0.75))
    assert main(["run", SCENE, "--mode", "fmu", "--coupling", "jacobi", "--out", "given", "--fmu-dir", "fd",
                 "--retry-substeps", "3", "--drives-in-plant", "4", "--replace", f"ctrl={fmu_file}"]) == 0
    [(args, kwargs)] = calls
    scene = args[0]
    assert scene.name == SCENE and _model(scene, "plant") == "ActuatedFiveBarPlant"
    assert next(c for c in scene.system.components if c.name == "plant").parameters["substeps"] == 4
    assert _model(scene, "ctrl") == str(fmu_file.resolve()) and "drive1" not in [c.name for c in scene.system.components]
    assert kwargs == {"mode": "fmu", "out_dir": Path("given"), "coupling": "jacobi", "fmu_dir": "fd",
                      "progress": None, "retry_substeps": 3}
    assert capsys.readouterr().out == (f"{SCENE} [fmu]: e_ef 0.5 mm, tau_ef 0.25 N m, e_ss 0.125 mm (not settled), "
                                       "2.00 s wall (4.5x real time, compiled in 0.75 s) -> given\n")


@pytest.mark.parametrize("options, folder", [
    ([], SCENE),
    (["--drives-in-plant", "2"], f"{SCENE}_drives_in_plant"),
    (["--replace", "ctrl=FMU"], f"{SCENE}_replaced"),
    (["--mode", "fmu", "--native"], f"{SCENE}_native"),
    (["--drives-in-plant", "2", "--replace", "ctrl=FMU", "--mode", "fmu", "--native"],
     f"{SCENE}_drives_in_plant_replaced_native"),
])
def test_run_without_out_writes_to_the_folder_named_by_its_options(options, folder, tmp_path, monkeypatch, record,
                                                                   fmu_file, capsys):
    """Without ``--out`` a run writes to ``out/SCENE`` with a suffix for each of
    ``--drives-in-plant``, ``--replace`` and ``--native``, in that order; the defaults are
    in process, Gauss-Seidel, no FMU folder, no retries; ``--native`` builds into
    fmus/build/native.  Catches a suffix dropped, misspelt or reordered, the folder
    built wrong, or a default changed."""
    monkeypatch.chdir(tmp_path)
    calls = record("scenarios.run.runner", "run_scene", _outcome(settled=True, t_settle_s=0.125))
    native = record("fmus.native.run", "with_native_fmus", lambda scene, out: scene)
    assert main(["run", SCENE, *[o.replace("=FMU", f"={fmu_file}") for o in options]]) == 0
    [(_, kwargs)] = calls
    mode = "fmu" if "--native" in options else "inprocess"
    assert kwargs == {"mode": mode, "out_dir": Path("out") / folder, "coupling": "gauss-seidel", "fmu_dir": None,
                      "progress": None, "retry_substeps": None}
    assert [a[1] for a, _ in native] == ([DEFAULT_NATIVE_OUT] if "--native" in options else [])
    assert capsys.readouterr().out.endswith(f"(settled 0.12 s after the stop), 2.00 s wall (4.5x real time) -> "
                                            f"{Path('out') / folder}\n")


def test_a_native_run_builds_into_the_native_folder_of_its_fmu_dir(tmp_path, monkeypatch, record):
    """Catches ``--fmu-dir`` not taking effect on where a native run's FMUs are built."""
    monkeypatch.chdir(tmp_path)
    record("scenarios.run.runner", "run_scene", _outcome())
    native = record("fmus.native.run", "with_native_fmus", lambda scene, out: scene)
    assert main(["run", SCENE, "--mode", "fmu", "--native", "--fmu-dir", "mine", "--out", "o"]) == 0
    assert [(a[0].name, a[1]) for a, _ in native] == [(SCENE, Path("mine") / "native")]


def test_bare_parcosim_is_a_run_of_the_default_scene(tmp_path, monkeypatch, record):
    """Catches bare ``parcosim`` running another scene, or into another folder."""
    monkeypatch.chdir(tmp_path)
    calls = record("scenarios.run.runner", "run_scene", _outcome())
    assert main([]) == 0
    [(args, kwargs)] = calls
    assert args[0].name == DEFAULT_SCENE and kwargs["out_dir"] == Path("out") / DEFAULT_SCENE


def _sweep_result(completed=3):
    e = {"n": completed, "median": 0.5, "p05": 0.25, "p95": 0.75}
    return SimpleNamespace(scene=SCENE, summary={"e_ef_mm": e, "samples": 3, "completed": completed,
                                                 "failed": 3 - completed}, computed=[1, 2], rows=[])


def test_sweep_passes_every_option_to_run_sweep(tmp_path, monkeypatch, record, capsys):
    """Catches a sweep option (samples, U, seed, distribution, perturb file, mode, scheduler,
    workers, stop time, folder) not passed on or passed as another, and the default folder
    ``out/sweep_SCENE_U`` built wrong."""
    monkeypatch.chdir(tmp_path)
    calls = record("scenarios.batch.sweep", "run_sweep", _sweep_result())
    assert main(["sweep", SCENE, "--samples", "3", "--uncertainty", "0.05", "--seed", "7", "--distribution", "normal",
                 "--perturb", "p.toml", "--mode", "fmu", "--scheduler", "tcp://h:1", "--workers", "2",
                 "--stop-time", "0.5", "--out", "sw"]) == 0
    assert main(["sweep", SCENE, "--samples", "1", "--uncertainty", "1.0"]) == 0
    (args, kwargs), (default_args, defaults) = calls
    assert args == (SCENE, 3, 0.05) and callable(kwargs.pop("progress"))
    assert kwargs == {"seed": 7, "distribution": "normal", "perturb": "p.toml", "mode": "fmu", "out_dir": "sw",
                      "scheduler": "tcp://h:1", "workers": 2, "stop_time": 0.5}
    assert default_args == (SCENE, 1, 1.0) and callable(defaults.pop("progress"))
    assert defaults == {"seed": 0, "distribution": None, "perturb": None, "mode": "inprocess",
                        "out_dir": "out/sweep_bench_circle_TCMDx_U1", "scheduler": None, "workers": None,
                        "stop_time": None}
    out = capsys.readouterr().out.splitlines()
    assert out == [f"{SCENE} U=0.05: 3 samples (2 run now), 3 completed, 0 failed; e_ef median 0.5 mm "
                   "(5-95 %: 0.25-0.75) -> sw/sweep.csv",
                   f"{SCENE} U=1: 3 samples (2 run now), 3 completed, 0 failed; e_ef median 0.5 mm "
                   "(5-95 %: 0.25-0.75) -> out/sweep_bench_circle_TCMDx_U1/sweep.csv"]


def test_report_passes_its_options_to_write_report(tmp_path, monkeypatch, record, capsys):
    """Catches the report's folder, mode, scheduler or workers not taking effect, and what
    write_report returns not printed."""
    monkeypatch.chdir(tmp_path)
    calls = record("scenarios.batch.report", "write_report", "the report path")
    assert main(["report", "--mode", "fmu", "--out", "rep", "--scheduler", "tcp://h:2", "--workers", "3"]) == 0
    assert main(["report"]) == 0
    (args, kwargs), (default_args, defaults) = calls
    assert args == ("rep", "fmu") and callable(kwargs.pop("progress"))
    assert kwargs == {"scheduler": "tcp://h:2", "workers": 3}
    assert default_args == ("out/report", "inprocess") and callable(defaults.pop("progress"))
    assert defaults == {"scheduler": None, "workers": None}
    assert capsys.readouterr().out == "the report path\n" * 2


def test_export_ssp_passes_the_scene_path_and_options_of_each_kind_of_package(tmp_path, monkeypatch, record,
                                                                              fmu_file, capsys):
    """The chain package gets the scene (with its replaced instance), the path and the FMU
    folder; the per-component package also the sub-steps, the internal observer and
    ``native``.  Catches an option dropped or swapped, and the per-component options
    accepted (and ignored) without ``--per-component``."""
    monkeypatch.chdir(tmp_path)
    chain = record("scenarios.packaging.chain", "export_package", "chain.ssp")
    per = record("scenarios.packaging.per_component", "export_per_component", "per.ssp")
    assert main(["export-ssp", SCENE, "a.ssp", "--fmu-dir", "fd", "--replace", f"ctrl={fmu_file}"]) == 0
    assert main(["export-ssp", SCENE, "b.ssp", "--per-component", "--substeps", "5", "--internal-observer",
                 "--native", "--drives-in-plant", "2"]) == 0
    [(args, kwargs)] = chain
    assert args[1:] == ("a.ssp", "fd") and kwargs == {} and _model(args[0], "ctrl") == str(fmu_file.resolve())
    [(args, kwargs)] = per
    assert args[1:] == ("b.ssp", None, 5, True) and kwargs == {"native": True}
    assert _model(args[0], "plant") == "ActuatedFiveBarPlant"
    assert capsys.readouterr().out == "chain.ssp\nper.ssp\n"
    for option in (["--substeps", "5"], ["--internal-observer"], ["--native"]):
        assert main(["export-ssp", SCENE, "c.ssp", *option]) == 2
    assert len(chain) == 1


def test_export_fmu_and_build_plant_pass_the_scene_or_spec_and_the_path(tmp_path, monkeypatch, record, capsys):
    """Catches the system, the path or the FMI version not passed on, or the native and
    the pythonfmu exports swapped."""
    monkeypatch.chdir(tmp_path)
    plain = record("fmus.systemfmu.export", "export_fmu", "plain.fmu")
    native = record("fmus.native.loopbuild", "export_native_fmu", "native.fmu")
    spec = record("fmus.export.specfmu", "build_plant_fmu", "plant.fmu")
    assert main(["export-fmu", SCENE, "a.fmu"]) == 0
    assert main(["export-fmu", SCENE, "b.fmu", "--native", "--fmi-version", "3", "--drives-in-plant", "2"]) == 0
    assert main(["build-plant", "bench_5r", "p.fmu"]) == 0
    [(args, kwargs)] = plain
    assert args[1:] == ("a.fmu",) and kwargs == {} and _model(SimpleNamespace(system=args[0]), "plant") == "FiveBarPlant"
    [(args, kwargs)] = native
    assert args[1:] == ("b.fmu",) and kwargs == {"fmi_version": 3}
    assert _model(SimpleNamespace(system=args[0]), "plant") == "ActuatedFiveBarPlant"
    assert spec == [(("bench_5r", "p.fmu"), {})]
    assert capsys.readouterr().out == "plain.fmu\nnative.fmu\nplant.fmu\n"


def test_build_builds_into_the_folder_given_or_its_default_and_prints_each_fmu(tmp_path, monkeypatch, record, capsys):
    """Catches ``--out`` or ``--fmi-version`` not taking effect, the native and the
    pythonfmu builds swapped, or a default folder other than fmus/build/ (native:
    fmus/build/native)."""
    monkeypatch.chdir(tmp_path)
    plain = record("fmus.export.build", "build_all", ["A.fmu", "B.fmu"])
    native = record("fmus.native.build", "build_native_all", ["N.fmu"])
    for argv in (["build", "--out", "o"], ["build"], ["build", "--native", "--fmi-version", "3", "--out", "n"],
                 ["build", "--native"]):
        assert main(argv) == 0
    assert plain == [(("o",), {}), ((DEFAULT_OUT,), {})]
    assert native == [(("n", 3), {}), ((DEFAULT_NATIVE_OUT, 2), {})]
    assert capsys.readouterr().out == "A.fmu\nB.fmu\n" * 2 + "N.fmu\n" * 2


def test_trade_workspace_and_demo_pass_their_options(tmp_path, monkeypatch, record, capsys):
    """Catches ``--quick``, the folder, the scene, the circles or the preset not taking
    effect, and a pendulum scene's trade not sent to the pendulum's own study."""
    monkeypatch.chdir(tmp_path)
    row = {"setting": "defaults", "wall_s": 1.5, "rms_err_m": 2e-4, "pareto": True}
    trade = record("scenarios.studies.trade", "run_trade",
                   SimpleNamespace(scene=SCENE, stop_time=1.0, rows=[row, {**row, "setting": "x", "pareto": False}],
                                   row=lambda name: row))
    pendulum = record("scenarios.studies.pendulum_trade", "run_pendulum_trade",
                      {"fidelity": [{"setting": "a", "wall_s": 0.5}, {"setting": "b", "wall_s": 0.25}]})
    workspace = record("scenarios.studies.workspace", "plot_workspace", SimpleNamespace(summary=lambda: "ws"))
    demo = record("scenarios.examples.plant_demo", "run")
    assert main(["trade", SCENE, "--quick", "--out", "t"]) == 0
    assert main(["trade", "pendulum_balance", "--out", "pt"]) == 0
    assert main(["workspace", "thesis_sim", "--out", "w", "--circle", "0.1,0.2,0.03", "--circle", "0,0.25,0.5"]) == 0
    assert main(["demo", "--out", "d", "--preset", "bench"]) == 0
    [(args, kwargs)] = trade
    assert args == (SCENE,) and callable(kwargs.pop("progress")) and kwargs == {"quick": True, "out_dir": "t"}
    [(args, kwargs)] = pendulum
    assert args == ("pendulum_balance",) and callable(kwargs.pop("progress"))
    assert kwargs == {"quick": False, "out_dir": "pt"}
    assert workspace == [(("thesis_sim", "w"), {"circles": [(0.1, 0.2, 0.03), (0.0, 0.25, 0.5)]})]
    assert demo == [(("d", "bench"), {})]
    assert capsys.readouterr().out.splitlines() == [
        f"{SCENE} 0-1 s: defaults 1.50 s wall, RMS deviation 0.0002 m; front: defaults -> t/trade.md",
        "pendulum_balance: a 0.50 s, b 0.25 s -> pt/trade.md", "ws"]


class _Terminal(io.StringIO):
    """A stderr that says it is a terminal."""

    def isatty(self):
        return True


def test_on_a_terminal_a_run_shows_its_progress_and_a_long_command_its_status_line(tmp_path, monkeypatch, record,
                                                                                  capsys):
    """On a terminal ``run`` passes a progress bar to ``run_scene`` (30 marks, the percentage)
    after saying it is loading; ``build`` says what it does on one status line, cleared
    before its output, which goes to stdout as without a terminal.  Catches the progress or
    the status line lost, or the command's output swallowed by the status line."""
    monkeypatch.chdir(tmp_path)
    calls = record("scenarios.run.runner", "run_scene", lambda *args, **kwargs: kwargs["progress"](0.5) or _outcome())
    record("fmus.export.build", "build_all", ["A.fmu"])
    err = _Terminal()
    monkeypatch.setattr("sys.stderr", err)
    assert main(["run", SCENE, "--out", "o"]) == 0
    assert callable(calls[0][1]["progress"])
    assert err.getvalue() == (f"{SCENE}: loading and initialising (inprocess)...\r{SCENE} [{'#' * 15}{'.' * 15}]  "
                              "50.0 %")
    err.seek(0)
    err.truncate()
    assert main(["build", "--out", "b"]) == 0
    assert err.getvalue() == "parcosim build: building the FMUs ...\r\033[K"
    assert capsys.readouterr().out.endswith("-> o\nA.fmu\n")


def test_identify_motor_is_parcosims_command_with_its_own_options(capsys):
    """Catches ``parcosim identify-motor ...`` not handed to motor.cli's identify_main with the
    arguments after the command word (then the run parser refuses it, or the word is passed on):
    its JSON is identify_main's, and its errors are identify-motor's own."""
    from motor.cli import identify_main

    data = str(Path(__file__).resolve().parents[2] / "motor" / "data" / "motor2.csv")
    argv = ["--data", data, "--settling-time", "0.198"]
    assert identify_main(argv) == 0
    direct = capsys.readouterr().out
    assert main(["identify-motor", *argv]) == 0
    assert capsys.readouterr().out == direct and direct.startswith("{")
    assert main(["identify-motor", "--data", "does-not-exist.csv"]) == 2
    assert capsys.readouterr().err.startswith("parcosim identify-motor: error: ")


@pytest.mark.parametrize("options, folder", [([], SCENE), (["--replace", "ctrl=FMU"], f"{SCENE}_replaced")])
def test_a_run_without_out_whose_folder_is_a_file_is_refused_before_it_runs(options, folder, tmp_path,
                                                                           monkeypatch, record, fmu_file, capsys):
    """Catches the check before a run given another path than the folder it writes (out/, or
    a folder without the suffixes of its options): a file at ``out/FOLDER`` must refuse the
    run, naming that path, before anything is simulated."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / folder).write_text("not a folder")
    calls = record("scenarios.run.runner", "run_scene", _outcome(settled=True, t_settle_s=0.125))
    assert main(["run", SCENE, *[o.replace("=FMU", f"={fmu_file}") for o in options]]) == 2
    assert calls == []
    path = Path("out") / folder
    assert f"{path} is not writable: {path} is a file, not a folder" in capsys.readouterr().err
