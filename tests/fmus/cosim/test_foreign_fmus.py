"""Foreign FMUs in scenes (issue 12.1-12.4): FMUs that parcosim did not build, compiled
here from C at test time with the system compiler and the FMI headers that fmpy ships.

* ``DCDrive`` (tests/support/cfmu/dcdrive.c), written from docs/motor.md alone, replaces
  both drives of ``bench_circle_TCMDx``: in process (our components in process, the C
  drives through fmpy, in one run) and in ``--mode fmu``, the path equals ours.
* ``Threshold`` (threshold.c) has Integer and Boolean inputs and outputs and an output
  without declared dependencies: typed connections, the t = 0 row consistent with the
  connected inputs, the feedthrough an importer must assume.
"""
from __future__ import annotations

import dataclasses
import sys
import warnings
import zipfile

import numpy as np
import pytest

from fmus.cosim.master import AlgebraicLoopError, simulate
from fmus.cosim.system import Component, Connection, System
from parcosim.cli import main
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import with_fmu_files
from tests.support.paths import TESTS

sys.path.insert(0, str(TESTS / "support" / "cfmu"))
from build import build_c_fmu, compiler  # noqa: E402

pytestmark = [pytest.mark.slow, pytest.mark.fmu]

#: The path of the bench scene with the C drives may differ from ours by at most this [m].
PATH_TOLERANCE = 1e-9


@pytest.fixture(scope="module")
def c_fmus(tmp_path_factory):
    if compiler() is None:
        pytest.skip("no C compiler (cc or gcc) on the PATH: the foreign test FMUs are built from C")
    out = tmp_path_factory.mktemp("c_fmus")
    return {model: build_c_fmu(model, out) for model in ("DCDrive", "Threshold")}


@pytest.fixture(scope="module")
def bench_inprocess():
    return simulate(get_scene("bench_circle_TCMDx").system)


def _c_drives(c_fmus):
    return with_fmu_files(get_scene("bench_circle_TCMDx"),
                          {"drive1": c_fmus["DCDrive"], "drive2": c_fmus["DCDrive"]})


def _path_deviation(a, b):
    return max(np.abs(a["plant.x"] - b["plant.x"]).max(), np.abs(a["plant.y"] - b["plant.y"]).max())


@pytest.mark.parametrize("mode", ["inprocess", "fmu"])
def test_c_drive_replaces_both_bench_drives(mode, c_fmus, bench_inprocess, built_fmus):
    """Catches a foreign C drive that is wired wrong or sent parameters it does not have."""
    fmu_dir = next(iter(built_fmus.values())).parent
    with pytest.warns(UserWarning, match=r"skipped: drive1 \(DCDrive.fmu\): method; drive2 \(DCDrive.fmu\): method"):
        result = simulate(_c_drives(c_fmus).system, mode=mode, fmu_dir=fmu_dir)
    assert result.completed and result.time[-1] == pytest.approx(11.0)   # 8 turns, 3 s to settle
    assert _path_deviation(result, bench_inprocess) <= PATH_TOLERANCE
    # The drives did their job: the currents moved and the circle was tracked.
    assert np.abs(result["drive1.i"]).max() > 0.1
    assert result.order == bench_inprocess.order


def test_parcosim_run_replace(c_fmus, tmp_path, capsys):
    """Catches parcosim run --replace failing on a foreign drive or skipping parameters silently."""
    out = tmp_path / "run"
    assert main(["run", "bench_circle_TCMDx", "--replace", f"drive1={c_fmus['DCDrive']}",
                 "--replace", f"drive2={c_fmus['DCDrive']}", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "parcosim: warning: parameters the foreign FMUs do not have are skipped" in captured.err
    assert (out / "result.csv").exists()


def test_a_missing_variable_is_one_line_naming_it_and_the_fmus_variables(c_fmus, tmp_path, capsys):
    """Catches a missing variable of a foreign FMU refused with a traceback or without its variables."""
    assert main(["run", "bench_circle_TCMDx", "--replace", f"drive1={c_fmus['Threshold']}",
                 "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert "has no variable" in err and "drive1." in err
    assert "has no variable 'i_ref'; its variables: input u, k, enable; parameter threshold; output y, count, " \
           "above" in err


@pytest.mark.parametrize("argv, message", [
    (["--replace", "nosuch=X.fmu"], "no instance 'nosuch'; instances: traj, deriv"),
    (["--replace", "drive1"], "write INSTANCE=PATH.fmu"),
    (["--replace", "drive1=/no/such.fmu"], "not an existing .fmu file"),
])
def test_replace_mistakes_exit_2(argv, message, tmp_path, capsys):
    """Catches a malformed --replace accepted or ending in a traceback instead of exit 2."""
    assert main(["run", "bench_circle_TCMDx", *argv, "--out", str(tmp_path)]) == 2
    assert message in capsys.readouterr().err


def test_exports_carry_the_foreign_fmu_or_say_why_not(c_fmus, tmp_path, capsys, built_fmus):
    """Catches an export that drops a foreign FMU or packs one it cannot run."""
    fmu_dir = str(next(iter(built_fmus.values())).parent)
    replace = ["--replace", f"drive1={c_fmus['DCDrive']}"]
    path = tmp_path / "drive.ssp"
    assert main(["export-ssp", "bench_circle_TCMDx", str(path), "--per-component", "--substeps", "4",
                 "--fmu-dir", fmu_dir, *replace]) == 0
    with zipfile.ZipFile(path) as z, zipfile.ZipFile(z.open("resources/drive1.fmu")) as drive:
        assert b'modelName="DCDrive"' in drive.read("modelDescription.xml")
    # fmpy's SSP runner runs the package as our Jacobi master runs the scene at the
    # package's base step with its sample phases: to the last bits of the reference, which
    # the runner takes at its summed clock (time += h) and the master at k h (4e-15 m in 0.3 s;
    # a step of delay more or less moves x by millimetres).
    from fmus.ssp.export import read_ssp_experiment, read_ssp_parameters
    from fmus.ssp.run import simulate_ssp_fmpy

    run = simulate_ssp_fmpy(path, stop_time=0.3)
    bound = read_ssp_parameters(path)
    scene = with_fmu_files(get_scene("bench_circle_TCMDx"), {"drive1": c_fmus["DCDrive"]})
    phased = tuple(dataclasses.replace(c, parameters={**c.parameters, **{
        k: bound[f"{c.name}.{k}"] for k in ("sample_phase",) if f"{c.name}.{k}" in bound}})
        for c in scene.system.components)
    system = dataclasses.replace(scene.system, components=phased, stop_time=0.3, step=read_ssp_experiment(path)[2])
    with pytest.warns(UserWarning, match="method"):
        master = simulate(system, mode="fmu", coupling="jacobi", fmu_dir=fmu_dir)
    rows = min(len(run["plant.x"]), len(master["plant.x"]) - 1)    # fmpy may take a step more (t += h)
    np.testing.assert_allclose(run["plant.x"][:rows], master["plant.x"][1:rows + 1], rtol=0.0, atol=1e-12)
    capsys.readouterr()
    assert main(["export-ssp", "bench_circle_TCMDx", str(tmp_path / "p.ssp"), *replace]) == 0
    with zipfile.ZipFile(tmp_path / "p.ssp") as z, zipfile.ZipFile(z.open("resources/control.fmu")) as control:
        assert "resources/foreign/drive1.fmu" in control.namelist()     # the C drive travels inside
    assert main(["export-fmu", "bench_circle_TCMDx", str(tmp_path / "loop.fmu"), *replace]) == 0
    assert main(["export-ssp", "bench_circle_TCMDx", str(tmp_path / "q.ssp"),
                 "--replace", f"plant={c_fmus['DCDrive']}"]) == 2
    assert "the plant is an FMU file" in capsys.readouterr().err


def test_the_exports_with_c_drives_track_in_the_tools(c_fmus, tmp_path):
    """With the C drives in the scene, the package keeps its shape (the drives inside
    ``control``, run there through fmpy; the plant driven by their torques): over 2 s in
    fmpy's plain SSP runner its tracking is ours within 5 %; the one-FMU export is the
    master's run with the C drives bit for bit."""
    from fmpy import simulate_fmu

    from fmus.systemfmu.export import export_fmu
    from scenarios.studies.tools import compare, short

    scene = dataclasses.replace(short(_c_drives(c_fmus), 2.0), window=(1.0, 2.0))
    with pytest.warns(UserWarning, match="method"):     # our drive's parameter the C drive lacks
        (tool, m, ours, error), = compare(scene, ("fmpy",), isolated=False, out_dir=tmp_path)
    assert error is None and m["completed"]
    assert 0.95 <= m["e_ef_mm"] / ours["e_ef_mm"] <= 1.05
    assert 0.95 <= m["tau_ef_Nm"] / ours["tau_ef_Nm"] <= 1.05
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        master = simulate(scene.system)
        fmu = export_fmu(scene.system, tmp_path / "loop.fmu")
    run = simulate_fmu(str(fmu), stop_time=2.0, output_interval=1e-3, output=["x", "y"])
    assert np.array_equal(run["x"], master["plant.x"]) and np.array_equal(run["y"], master["plant.y"])


# --- Integer and Boolean ------------------------------------------------------------------

def _threshold_system(c_fmus, x0, spread):
    """traj -> a.u, b.u; a.above (Boolean) -> b.enable; a.count (Integer) -> b.k."""
    path = str(c_fmus["Threshold"])
    components = (Component("traj", "Trajectory", {"kind": "circle"}),
                  Component("a", path, {"threshold": x0 - 0.5 * spread, "enable": True, "k": 1}),
                  Component("b", path, {"threshold": x0 - 0.2 * spread}))
    connections = (Connection("traj.x_d", "a.u"), Connection("traj.x_d", "b.u"),
                   Connection("a.above", "b.enable"), Connection("a.count", "b.k"))
    record = ("traj.x_d", "a.above", "a.count", "a.y", "b.above", "b.count")
    return System(components, connections, record, stop_time=3.0)


@pytest.mark.parametrize("mode", ["inprocess", "fmu"])
def test_integer_and_boolean_connections(mode, c_fmus, built_fmus):
    """Catches Integer or Boolean connections passed as Real (or not at all) between FMUs."""
    trajectory = simulate(System((Component("traj", "Trajectory", {"kind": "circle"}),), (), ("traj.x_d",), 3.0))
    x_d = trajectory["traj.x_d"]
    x0, spread = x_d[0], np.ptp(x_d)
    result = simulate(_threshold_system(c_fmus, x0, spread), mode=mode,
                      fmu_dir=next(iter(built_fmus.values())).parent)
    assert result.completed
    assert result.order == ("traj", "a", "b") or result.order.index("a") < result.order.index("b")
    np.testing.assert_array_equal(result["traj.x_d"], x_d)
    # An independent account of the two counters from the reference alone.  a steps before
    # traj (it reads x_d at the step's start); b after a (a's outputs feed it directly).
    above_a = x_d > x0 - 0.5 * spread
    above_b = above_a & (x_d > x0 - 0.2 * spread)
    count_a = np.concatenate([[0], np.cumsum(above_a[:-1])])
    count_b = np.concatenate([[0], np.cumsum(np.where(above_b[:-1], count_a[1:], 0))])
    np.testing.assert_array_equal(result["a.count"], count_a)
    np.testing.assert_array_equal(result["b.count"], count_b)
    assert 0 < count_a[-1] < len(x_d) - 1, "the input must cross the threshold"
    # t = 0: a's Boolean output was computed from the connected x_d(0), not from u's start 0.
    assert result["a.above"][0] == 1.0 and result["b.above"][0] == float(above_b[0])


def test_outputs_without_dependencies_close_an_algebraic_loop(c_fmus):
    """Catches outputs without declared dependencies taken as free of feedthrough."""
    path = str(c_fmus["Threshold"])
    system = System((Component("a", path, {}), Component("b", path, {})),
                    (Connection("a.above", "b.enable"), Connection("b.above", "a.enable")), ("a.count",), 0.01)
    with pytest.raises(AlgebraicLoopError, match=r"b.above -> a.enable; a.above -> b.enable|"
                                                 r"a.above -> b.enable; b.above -> a.enable"):
        simulate(system)


def test_a_connection_joins_one_type(c_fmus):
    """Catches a connection between variables of two types accepted."""
    path = str(c_fmus["Threshold"])
    system = System((Component("a", path, {}), Component("b", path, {})),
                    (Connection("a.count", "b.u"),), ("b.y",), 0.01)
    with pytest.raises(ValueError, match=r"a.count \(Integer\) -> b.u \(Real\): a connection joins variables "
                                         "of one type"):
        simulate(system)


# --- the build and foreign files -------------------------------------------------------------

def test_build_leaves_a_foreign_fmu_alone_and_fmu_mode_refuses_it(c_fmus, tmp_path, capsys):
    """Catches the build overwriting a foreign FMU, or FMU mode running it as ours."""
    from fmus.export.build import ForeignFmuError, build_fmu, ensure_built

    foreign = tmp_path / "DCMotorDrive.fmu"
    foreign.write_bytes(c_fmus["DCDrive"].read_bytes())
    before = foreign.read_bytes()
    with pytest.warns(UserWarning, match="DCMotorDrive.fmu was not built by parcosim: left alone"):
        assert build_fmu("DCMotorDrive", tmp_path) is None
    assert foreign.read_bytes() == before
    with pytest.raises(ForeignFmuError, match="was not built by parcosim; to run it in place of DCMotorDrive, "
                                              "use --replace"):
        ensure_built(["DCMotorDrive"], tmp_path)
    assert main(["run", "bench_circle_TCMDx", "--mode", "fmu", "--fmu-dir", str(tmp_path),
                 "--out", str(tmp_path / "out")]) == 2
    assert "not built by parcosim" in capsys.readouterr().err
    assert foreign.read_bytes() == before
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert build_fmu("Trajectory", tmp_path) == tmp_path / "Trajectory.fmu"   # ours: built, no warning


def test_a_foreign_fmus_refused_step_is_reported_in_its_own_words(c_fmus):
    """A foreign FMU has no String outputs ``error`` and ``refusal``: its refusal is the message
    it logged, with no record of a quantity.  Catches the back end looking for those outputs
    in a way that fails on an FMU without them (seed 3601's survivor [211]: the run's error
    then names a Python exception instead of the FMU's words)."""
    scene = _c_drives(c_fmus)
    components = tuple(dataclasses.replace(c, parameters={**c.parameters, "T": 0.0025}) if c.name == "drive1" else c
                       for c in scene.system.components)
    system = dataclasses.replace(scene.system, components=components, stop_time=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # the parameters the C drive does not have are skipped
        result = simulate(system, mode="inprocess")
    error = result.error
    assert (error.kind.value, error.instance, error.time, error.variable) == ("refused", "drive1", 0.0, None)
    assert "the step 0.001 s must divide T = 0.0025 s (t = 0 s)" in error.message
    assert len(result.time) == 1
