"""FMUs in a host with no Python in its process (issue 28, item 4).

``tests/native_host/host.c`` is a small C program built here with the C compiler: it loads
FMUs through libcosim's C API (``libcosimc.so`` from the libcosimpy wheel), steps the
execution, writes outputs to CSV and reports what its process had mapped
(``tests/native_host/host.py``).  Each test checks the host's result against an expectation
formed without libcosim: a closed-form solution, or the same FMU's pythonfmu twin run in
fmpy, or the tracking error of ``parcosim run``.
"""
from __future__ import annotations

import math
import os
import sysconfig
from pathlib import Path

import numpy as np
import pytest

from fmus.native.models import NATIVE
from tests.native_host.host import HostUnavailable, build_host, config_text, run_host

pytestmark = [pytest.mark.fmu]

H = 1e-3            # s: the communication step
TAU_A, TAU_B, U = 0.01, 0.02, 2.0


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    try:
        return build_host(tmp_path_factory.mktemp("host"))
    except HostUnavailable as exc:
        pytest.skip(str(exc))


@pytest.fixture(scope="module")
def lowpass(tmp_path_factory):
    """The C low-pass FMU of benchmarks/baseline_fmu (y' = (u - y) / tau, exact per step)."""
    from benchmarks.cold_start import build_baseline

    return build_baseline(tmp_path_factory.mktemp("lowpass"))


def chained_lowpass_config(fmu: Path, stop: float) -> str:
    return config_text(stop, step=H, slaves=[("a", fmu), ("b", fmu)], connections=[("a.y", "b.u")],
                       reals=[("a.u", U), ("a.tau", TAU_A), ("b.tau", TAU_B)], outputs=["a.y", "b.y"])


def chained_lowpass_expected(steps: int):
    """Two low-passes in series under a fixed-step Jacobi master: b holds over each step the
    value a had at the step's start (libcosim's fixed-step algorithm)."""
    a = b = 0.0
    rows = []
    for _ in range(steps):
        a, b = U + (a - U) * math.exp(-H / TAU_A), a + (b - a) * math.exp(-H / TAU_B)
        rows.append((a, b))
    return np.array(rows)


def test_the_host_runs_a_c_fmu_chain_with_no_python_in_its_process(host, lowpass, tmp_path):
    """Catches the C host loading libpython (so the claim "no Python" is false), or stepping the chained
    FMUs otherwise than the analytic low-pass chain."""
    run = run_host(host, tmp_path, chained_lowpass_config(lowpass, 0.05))
    assert run.report["steps"] == "50"
    assert run.columns["time"][-1] == pytest.approx(0.05, abs=1e-12)
    expected = chained_lowpass_expected(50)
    np.testing.assert_allclose(run.columns["a.y"], expected[:, 0], rtol=0, atol=1e-13)
    np.testing.assert_allclose(run.columns["b.y"], expected[:, 1], rtol=0, atol=1e-13)
    assert run.report["libpython_mapped"] == "0" and run.report["python_symbol"] == "0"
    assert run.fmu_binaries == ["lowpass.so"]       # the FMU's binary was loaded in this process


def test_the_mapping_check_sees_libpython_when_it_is_there(host, lowpass, tmp_path):
    """The same run with libpython preloaded: the report must say so (a check that cannot
    see libpython would pass every native FMU)."""
    libpython = Path(sysconfig.get_config_var("LIBDIR") or "") / (sysconfig.get_config_var("LDLIBRARY") or "")
    if not libpython.name.startswith("libpython") or not libpython.is_file():
        pytest.skip(f"this Python has no shared libpython ({libpython})")
    run = run_host(host, tmp_path, chained_lowpass_config(lowpass, 0.002),
                   env={**os.environ, "LD_PRELOAD": str(libpython)})
    assert int(run.report["libpython_mapped"]) > 0 and run.report["python_symbol"] == "1"


def test_the_host_names_what_it_cannot_find(host, lowpass, tmp_path):
    """Catches the C host running on (or crashing) when its configuration names a variable the FMU does not
    have."""
    config = chained_lowpass_config(lowpass, 0.01).replace("output b.y", "output b.nonsense")
    with pytest.raises(RuntimeError, match="nonsense"):
        run_host(host, tmp_path, config)


# --- the native FMUs (fmus.native: parcosim build --native) ------------------------------------

def twin_outputs(fmu: Path, inputs: dict, outputs: list, steps: int) -> np.ndarray:
    """The FMU run in fmpy, ``steps`` doSteps of H, ``inputs`` (name -> values) set before
    each; the ``outputs`` after initialisation (row 0) and after each step."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="twin")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    rows = [slave.getReal([vr[n] for n in outputs])]
    for k in range(steps):
        slave.setReal([vr[n] for n in inputs], [float(v[k]) for v in inputs.values()])
        slave.doStep(k * H, H)
        rows.append(slave.getReal([vr[n] for n in outputs]))
    slave.terminate()
    slave.freeInstance()
    return np.array(rows)


def test_a_native_derivator_in_the_c_host_equals_its_pythonfmu_twin_in_fmpy(host, lowpass, native_fmus, twin_fmus,
                                                                             tmp_path):
    """Two low-passes (step responses of different time constants) feed the native
    Derivator in libcosim; the pythonfmu Derivator, fed in fmpy the samples libcosim gave
    (each step holds the source's output at the step's start, 0 before the first), must give
    the same velocities and accelerations within 1e-12 of their peaks."""
    derivator = native_fmus["Derivator"]
    config = config_text(0.3, step=H, slaves=[("src1", lowpass), ("src2", lowpass), ("deriv", derivator)],
                         connections=[("src1.y", "deriv.q1"), ("src2.y", "deriv.q2")],
                         reals=[("src1.u", 0.5), ("src1.tau", 0.05), ("src2.u", -1.0), ("src2.tau", 0.02)],
                         outputs=["src1.y", "src2.y", "deriv.dq1", "deriv.ddq1", "deriv.dq2", "deriv.ddq2"])
    run = run_host(host, tmp_path / "run", config)
    assert run.report["libpython_mapped"] == "0" and run.report["python_symbol"] == "0"
    assert "Derivator.so" in run.fmu_binaries
    held = {q: np.concatenate([[0.0], run.columns[f"src{j}.y"][:-1]]) for j, q in ((1, "q1"), (2, "q2"))}
    names = ["dq1", "ddq1", "dq2", "ddq2"]
    twin = twin_outputs(twin_fmus["Derivator"], held, names, len(held["q1"]))[1:]
    for j, name in enumerate(names):
        peak = np.max(np.abs(twin[:, j]))
        assert peak > 1.0                         # the filters moved
        np.testing.assert_allclose(run.columns[f"deriv.{name}"], twin[:, j], rtol=0, atol=1e-12 * peak)


def test_a_native_trajectory_feeds_a_native_derivator_in_the_c_host_as_their_twins_do(host, native_fmus, twin_fmus,
                                                                                      tmp_path):
    """The reference circle (native Trajectory) differentiated by the native Derivator in
    libcosim, against the pythonfmu Trajectory run in fmpy, and the pythonfmu Derivator fed
    the samples libcosim gave the native one (each held over the step after it; the first,
    after initialisation, the twin's): every output within 1e-12 of its peak.  (The twins'
    circles differ in the last bits; the acceleration filter would magnify that by 1/h².)"""
    native = {m: native_fmus[m] for m in ("Trajectory", "Derivator")}
    steps = 1500
    config = config_text(steps * H, step=H, slaves=[("traj", native["Trajectory"]), ("deriv", native["Derivator"])],
                         connections=[("traj.x_d", "deriv.q1"), ("traj.y_d", "deriv.q2")],
                         outputs=["traj.x_d", "traj.y_d", "deriv.dq1", "deriv.ddq1", "deriv.dq2", "deriv.ddq2"])
    run = run_host(host, tmp_path / "run", config)
    assert run.report["libpython_mapped"] == "0" and set(run.fmu_binaries) == {"Trajectory.so", "Derivator.so"}
    python = {m: twin_fmus[m] for m in native}
    reference = twin_outputs(python["Trajectory"], {}, ["x_d", "y_d"], steps)
    held = {q: np.concatenate([[reference[0, j]], run.columns[f"traj.{name}"][:-1]])
            for j, (q, name) in enumerate((("q1", "x_d"), ("q2", "y_d")))}
    names = ["dq1", "ddq1", "dq2", "ddq2"]
    twin = np.column_stack([reference[1:], twin_outputs(python["Derivator"], held, names, steps)[1:]])
    for j, name in enumerate(["traj.x_d", "traj.y_d"] + [f"deriv.{n}" for n in names]):
        peak = np.max(np.abs(twin[:, j]))
        assert peak > 0.01, name                  # the circle moves the filters
        np.testing.assert_allclose(run.columns[name], twin[:, j], rtol=0, atol=1e-12 * peak, err_msg=name)


def test_a_native_trajectory_drives_a_native_position_controller_in_the_c_host_as_their_twins_do(
        host, native_fmus, twin_fmus, tmp_path):
    """The circle (native Trajectory) as the references of the native PositionController
    (its default, TCx on its table) in libcosim, the measured pose held at the bench's
    start; the pythonfmu controller, fed in fmpy the references libcosim gave (each held over
    the step after it, the first the twin Trajectory's after initialisation): torques,
    current references and errors within 1e-12 of their peaks, no Python in the host."""
    from controller.kinematics import Kinematics
    from controller.trajectories import BENCH_START
    from plant import get_preset

    angles = Kinematics(get_preset("bench")).inverse(*BENCH_START)
    measured = {"q1": angles[0], "q2": angles[2]}
    references = ["x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d"]
    names = ["tau1", "tau2", "i_ref1", "i_ref2", "e1", "e2"]
    steps = 1500
    config = config_text(steps * H, step=H, slaves=[("traj", native_fmus["Trajectory"]),
                                                    ("ctrl", native_fmus["PositionController"])],
                         connections=[(f"traj.{r}", f"ctrl.{r}") for r in references],
                         reals=[(f"ctrl.{q}", v) for q, v in measured.items()],
                         outputs=[f"traj.{r}" for r in references] + [f"ctrl.{n}" for n in names])
    run = run_host(host, tmp_path / "run", config)
    assert run.report["libpython_mapped"] == "0" and set(run.fmu_binaries) == {"Trajectory.so",
                                                                               "PositionController.so"}
    first = twin_outputs(twin_fmus["Trajectory"], {}, references, 0)[0]
    held = {r: np.concatenate([[first[j]], run.columns[f"traj.{r}"][:-1]]) for j, r in enumerate(references)}
    held.update({q: np.full(steps, v) for q, v in measured.items()})
    twin = twin_outputs(twin_fmus["PositionController"], held, names, steps)[1:]
    for j, name in enumerate(names):
        peak = np.max(np.abs(twin[:, j]))
        assert peak > 1e-3, name                  # the circle moves the law
        np.testing.assert_allclose(run.columns[f"ctrl.{name}"], twin[:, j], rtol=0, atol=1e-12 * peak, err_msg=name)


SCENE = "bench_circle_TCMDx"


def test_the_native_bench_loop_in_the_c_host_tracks_as_a_jacobi_master(host, native_fmus, tmp_path):
    """The bench loop (plant, drives, observers, derivator, controller, trajectory), every
    component a native FMU, wired as ``parcosim export-ssp --per-component`` wires it, loaded
    by libcosim from the SSP package in the C host: libcosim steps Jacobi (every FMU, then
    every connection; docs/ssp_tools.md), so the loop must track as our in-process master does
    with ``coupling="jacobi"`` (Python objects, no FMU): e_ef and tau_ef within 5 %.  (The
    Gauss-Seidel run, ``parcosim run``, tracks to 0.447 mm; a Jacobi tool adds a step of delay
    per connection: 40.0 mm.)"""
    from fmus.cosim.master import simulate
    from fmus.ssp.export import export_ssp
    from scenarios.run.metrics import scene_metrics
    from scenarios.run.runner import result_columns
    from scenarios.scenes.catalogue import get_scene

    scene = get_scene(SCENE)
    models = sorted({c.model for c in scene.system.components})
    missing = [m for m in models if m not in NATIVE]
    if missing:
        pytest.skip(f"no native FMU of {missing} yet")
    native = {m: native_fmus[m] for m in models}
    package = export_ssp(scene.system, tmp_path / "bench.ssp", fmus=native)
    run = run_host(host, tmp_path / "run", config_text(scene.system.stop_time, ssp=package,
                                                        outputs=list(scene.columns.values())))
    assert run.report["libpython_mapped"] == "0" and run.report["python_symbol"] == "0"
    assert set(run.fmu_binaries) == {f"{m}.so" for m in models}
    columns = {"t": np.array(run.columns["time"])}
    columns.update({name: np.array(run.columns[signal]) for name, signal in scene.columns.items()})
    ours = scene_metrics(scene, columns, 0.0, True)
    jacobi = simulate(scene.system, mode="inprocess", coupling="jacobi")
    expected = scene_metrics(scene, result_columns(scene, jacobi), jacobi.wall_s, jacobi.completed)
    for metric in ("e_ef_mm", "tau_ef_Nm"):
        assert 1 / 1.05 <= ours[metric] / expected[metric] <= 1.05, (metric, ours[metric], expected[metric])


def test_the_native_closed_loop_in_the_c_host_tracks_as_parcosim_run(host, native_loop_fmu, tmp_path):
    """The scene's whole loop as one native FMU (``parcosim export-fmu SCENE OUT.fmu --native``)
    stepped by libcosim in the C host over the scene's window: its tracking error is that of
    ``parcosim run`` (the Gauss-Seidel loop inside the FMU, in process), within 1e-9 relative."""
    from dataclasses import replace

    from scenarios.metrics import scene_metrics
    from scenarios.run import run_scene
    from scenarios.scenes import get_scene

    scene = get_scene(SCENE)
    stop = scene.window[1] + 1.0
    scene = replace(scene, system=replace(scene.system, stop_time=stop))
    signals = {"x": "x", "y": "y", "x_d": "traj.x_d", "y_d": "traj.y_d", "tau1": "ctrl.tau1", "tau2": "ctrl.tau2"}
    run = run_host(host, tmp_path / "run", config_text(stop, step=H, slaves=[("loop", native_loop_fmu)],
                                                        outputs=[f"loop.{s}" for s in signals.values()]))
    assert run.report["libpython_mapped"] == "0" and run.report["python_symbol"] == "0"
    assert run.fmu_binaries == ["ClosedLoop.so"]
    columns = {"t": np.array(run.columns["time"])}
    columns.update({name: np.array(run.columns[f"loop.{s}"]) for name, s in signals.items()})
    assert columns["t"][-1] == pytest.approx(stop, abs=1e-9)
    ours = scene_metrics(scene, columns, 0.0, True)["e_ef_mm"]
    expected = run_scene(scene, "inprocess", plots=False).metrics["e_ef_mm"]
    assert ours == pytest.approx(expected, rel=1e-9, abs=0.0)
