"""Scenes, their metrics and the `parcosim run` / `parcosim list` commands."""
import json
from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim.system import Component, System
from parcosim.cli import main
from scenarios.scenes import catalogue as scenes
from scenarios.run.metrics import rms_norm
from scenarios.run.runner import run_scene
from scenarios.scenes.catalogue import get_scene, scene_names
from scenarios.scenes.scene import Scene
from scenarios.batch.regression import STORED as STORED_METRICS


def _shortened(name, stop_time):
    scene = get_scene(name)
    return replace(scene, system=replace(scene.system, stop_time=stop_time))


def test_scene_names_cover_the_contract():
    """Catches a contract scene (thesis_sim_circle, 16 bench scenes) missing from the catalogue."""
    names = scene_names()
    assert "thesis_sim_circle" in names
    for s in ("PDq", "PDx", "TCq", "TCx", "PDMDq", "PDMDx", "TCMDq", "TCMDx"):
        assert f"bench_circle_{s}" in names and f"bench_triangle_{s}" in names
    with pytest.raises(ValueError, match="unknown scene 'bench_circle_XYZ'"):
        get_scene("bench_circle_XYZ")


def test_every_twin_scene_name_resolves_to_that_twin_scene():
    """Catches a twin scene name that resolves to the plain bench scene underneath (no LuGre drives) or to
    another strategy's."""
    from scenarios.scenes.twin import twin_scene_names

    names = twin_scene_names()
    assert len(set(names)) == 16 and set(names) <= set(scene_names())
    for name in names:
        scene = get_scene(name)
        # bench_real names its scene from the (strategy, kind) it was given; LuGre drives
        # tell the twin's scene from the bench scene underneath
        assert scene.name == name, name
        assert scene.system.component("drive1").parameters["friction"] == "lugre", name


@pytest.mark.parametrize("name", ["bench_real_square_PDq", "bench_real_circle_SMCq", "bench_real_circle_pdq",
                                  "bench_real_circle", "bench_real_circle_PDq_2", "bench_real_PDq_circle"])
def test_a_near_miss_twin_scene_name_is_refused_clearly(name):
    """Names near a twin scene's (an unknown kind, a strategy the twin lacks, wrong case, a
    missing, extra or swapped part) get the unknown-scene error pointing at `parcosim list`."""
    expected = f"unknown scene {name!r}; `parcosim list` prints the {len(scene_names())} scenes"
    with pytest.raises(ValueError) as refusal:
        get_scene(name)
    assert str(refusal.value) == expected


def test_ideal_actuator_scene_has_no_motors():
    """Catches motors or observers left in the ideal-actuator thesis scene."""
    models = {c.model for c in get_scene("thesis_sim_circle").system.components}
    assert models == {"Trajectory", "PositionController", "FiveBarPlant"}


@pytest.mark.parametrize("name", scene_names())
def test_every_scene_starts_and_runs(name):
    """Catches a catalogue scene that fails to start or gives non-finite positions."""
    outcome = run_scene(_shortened(name, 0.02))
    assert outcome.result.error is None
    assert np.all(np.isfinite(outcome.columns["x"]))


def test_metrics_are_the_thesis_formulas():
    """Catches e_ef or tau_ef computed over another window, divided by another count, or not the RMS norms
    of the thesis (7.31-7.32)."""
    scene = _shortened("bench_triangle_TCx", 0.3)
    scene = replace(scene, window=(0.1, 0.25))
    outcome = run_scene(scene)
    c = outcome.columns
    w = (c["t"] > 0.1 - 1e-9) & (c["t"] < 0.25 + 1e-9)
    assert w.sum() == 151
    ex, ey = c["x_d"][w] - c["x"][w], c["y_d"][w] - c["y"][w]
    expected = 1e3 * np.sqrt(np.sum(ex ** 2 + ey ** 2) / w.sum())
    assert outcome.metrics["e_ef_mm"] == pytest.approx(expected, rel=1e-12)
    assert outcome.metrics["tau_ef_Nm"] == pytest.approx(rms_norm(c["tau1"][w], c["tau2"][w]), rel=1e-12)
    assert outcome.metrics["tau_ef_Nm"] > 0.0


def test_thesis_sim_circle_exact_model_tracks_to_the_hold_error():
    """Exact model, ideal actuators: only the 1 ms hold is left, e_ef = 0.00572 mm measured;
    the bound is 15 % above it (the stored metrics of test_regression pin it to 1e-6; this
    bound keeps the claim if someone rewrites them).  Model error costs accuracy (thesis
    figures 18-23), monotonically: me20 0.264 mm (46x), me40 0.452 mm (79x); asserted 30x
    and 50x, so that the plant no longer seeing the model error fails by far."""
    outcome = run_scene("thesis_sim_circle")
    assert outcome.result.error is None
    assert outcome.metrics["e_ef_mm"] < 0.0066
    me20 = run_scene("thesis_sim_circle_me20").metrics["e_ef_mm"]
    me40 = run_scene("thesis_sim_circle_me40").metrics["e_ef_mm"]
    assert 30 * outcome.metrics["e_ef_mm"] < me20 < me40 and me40 > 50 * outcome.metrics["e_ef_mm"]


def test_run_command_writes_the_contract_files(tmp_path, monkeypatch):
    """Catches parcosim run writing result.csv without the contract columns, metrics.json without the
    contract keys, or no plot."""
    short = _shortened("bench_circle_PDx", 0.05)
    monkeypatch.setattr(scenes, "get_scene", lambda name: short)   # what the command looks up
    assert main(["run", "bench_circle_PDx", "--out", str(tmp_path)]) == 0
    header = (tmp_path / "result.csv").read_text().splitlines()[0].split(",")
    assert header[:1] == ["t"] and {"x", "y", "x_d", "y_d", "tau1", "tau2"} <= set(header)
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    for key in ("e_ef_mm", "tau_ef_Nm", "e_ss_mm", "wall_s", "realtime_factor"):
        assert key in metrics
    assert (tmp_path / "path.png").stat().st_size > 1000


def test_run_command_bad_scene_one_line(capsys):
    """Catches an unknown scene ending in a traceback or several lines instead of one line and exit 2."""
    assert main(["run", "bench_circle_nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown scene 'bench_circle_nope'" in err[0]


def test_stopped_run_keeps_what_was_recorded(tmp_path):
    # open loop 0.3 N m: the mechanism reaches a singular pose and the plant refuses
    """Catches a refused run that writes no rows, all of its planned rows, or metrics claiming completion."""
    components = (Component("traj", "Trajectory", {"kind": "hold"}),
                  Component("ctrl", "PositionController", {"strategy": "PDx"}),
                  Component("plant", "FiveBarPlant", {"preset": "bench", "x0": -0.002, "y0": 0.108,
                                                      "tau1": 0.3, "tau2": -0.3}))
    record = ("plant.x", "plant.y", "traj.x_d", "traj.y_d", "ctrl.tau1", "ctrl.tau2")
    system = System(components, (), record, stop_time=2.0)
    columns = dict(zip(("x", "y", "x_d", "y_d", "tau1", "tau2"), record))
    scene = Scene("open_loop", "open loop into a singularity", system, columns, (0.0, 2.0), 2.0, "none")
    outcome = run_scene(scene, out_dir=tmp_path)
    assert outcome.result.error.instance == "plant" and "plant" in str(outcome.result.error)
    rows = (tmp_path / "result.csv").read_text().splitlines()
    assert 10 < len(rows) - 1 == len(outcome.result.time) < 2001
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["completed"] is False and metrics["e_ef_mm"] is None and metrics["error"]["instance"] == "plant"


def test_fidelity_switches_remove_what_they_switch_off():
    """Catches a fidelity switch that leaves its model in the scene (an ideal drive still stepped, the
    encoder still wired, friction still on) or accepts an unknown value."""
    from scenarios.scenes.thesis import Fidelity, bench

    def models(**switches):
        return sorted(c.model for c in bench("TCx", fidelity=Fidelity(**switches)).system.components)

    assert models(electrics="ideal") == ["Derivator", "FiveBarPlant", "PositionController", "Trajectory"]
    assert "DCMotorDrive" not in models(electrics="ideal") and "CurrentObserver" not in models(electrics="ideal")
    assert "CurrentObserver" not in models(observer=False)
    assert "Derivator" not in models(derivator=False)
    scene = bench("TCx", fidelity=Fidelity(encoder=False, coulomb=False, viscous=False))
    sources = {c.source for c in scene.system.connections}
    assert "plant.q1_enc" not in sources and "plant.q1" in sources
    drive = scene.system.component("drive1").parameters
    assert drive["mu"] == 0.0 and drive["b"] == 0.0
    with pytest.raises(ValueError, match="electrics = 'magic'"):
        Fidelity(electrics="magic")


@pytest.mark.parametrize("switches", [dict(electrics="ideal"), dict(observer=False),
                                      dict(derivator=False, encoder=False), dict(link_inertias=False, m0=0.05),
                                      dict(viscous=False, coulomb=False)])
def test_reduced_fidelity_scenes_track(switches):
    """Catches a fidelity switch that breaks tracking of the bench circle."""
    from scenarios.scenes.thesis import Fidelity, bench

    scene = bench("PDx", fidelity=Fidelity(**switches))
    scene = replace(scene, system=replace(scene.system, stop_time=1.5), window=(1.0, 1.5))
    outcome = run_scene(scene)
    assert outcome.result.error is None
    # Full fidelity: 0.618 mm over this window; measured 0.229 (ideal electrics) to 0.636 mm
    # (no link inertias, m0 = 0.05 kg).  Leaving out an effect may not cost more than 30 %.
    assert outcome.metrics["e_ef_mm"] < 1.3 * 0.618


def test_export_ssp_command(tmp_path, built_fmus, capsys):
    """Catches export-ssp writing a package without the scene's components or failing."""
    import zipfile

    fmu_dir = next(iter(built_fmus.values())).parent
    path = tmp_path / "tcmdx.ssp"
    assert main(["export-ssp", "bench_circle_TCMDx", str(path), "--fmu-dir", str(fmu_dir)]) == 0
    names = zipfile.ZipFile(path).namelist()
    assert set(names) >= {"SystemStructure.ssd", "resources/control.fmu", "resources/plant.fmu"}
    per_component = tmp_path / "per_component.ssp"
    assert main(["export-ssp", "bench_circle_TCMDx", str(per_component), "--fmu-dir", str(fmu_dir),
                 "--per-component"]) == 0
    assert {"resources/ctrl.fmu", "resources/drive2.fmu"} <= set(zipfile.ZipFile(per_component).namelist())
    loop = tmp_path / "loop.fmu"
    assert main(["export-fmu", "thesis_sim_circle", str(loop)]) == 0
    assert "modelDescription.xml" in zipfile.ZipFile(loop).namelist()
    assert main(["export-ssp", "no_such_scene", str(tmp_path / "x.ssp")]) == 2
    assert "unknown scene 'no_such_scene'" in capsys.readouterr().err


def test_with_sample_time_sets_every_sample_time():
    """Catches with_sample_time missing a sampled component's T."""
    import importlib

    from fmus.export.build import SLAVES
    from fmus.cosim.master import simulate
    from scenarios.scenes.transforms import SAMPLE_TIME_MODELS, with_sample_time

    declaring_T = set()
    for model, module in SLAVES.items():
        slave = getattr(importlib.import_module(f"fmus.slaves.{module}"), model)(instance_name="probe")
        if any(v.name == "T" for v in slave.vars.values()):
            declaring_T.add(model)
    assert declaring_T == set(SAMPLE_TIME_MODELS)
    scene = with_sample_time(get_scene("bench_circle_TCMDx"), 2e-3)
    assert scene.system.step == 2e-3
    for c in scene.system.components:
        assert (c.parameters.get("T") == 2e-3) == (c.model in SAMPLE_TIME_MODELS), c.name
    result = simulate(replace(scene.system, stop_time=0.1))
    assert result.completed and len(result.time) == 51


def test_run_command_with_the_drives_in_the_plant(tmp_path, capsys):
    """Catches --drives-in-plant changing the tracking beyond 1 % of the separate drives', losing the drive
    columns, or accepted for a scene without drives."""
    out = tmp_path / "in_plant"
    assert main(["run", "bench_triangle_PDx", "--drives-in-plant", "8", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    # The drives' integration inside the plant changes e_ef by 0.1 % (0.6506 against the
    # separate drives' 0.6500 mm, tests/data/scene_metrics.json); 1 % asserted.
    separate = json.loads(STORED_METRICS.read_text())["scenes"]["bench_triangle_PDx"]["e_ef_mm"]
    assert metrics["completed"] and metrics["e_ef_mm"] == pytest.approx(separate, rel=0.01)
    header = (out / "result.csv").read_text().splitlines()[0].split(",")
    assert {"i1", "i2", "v1", "v2"} <= set(header)
    capsys.readouterr()
    assert main(["run", "thesis_sim_circle", "--drives-in-plant", "8", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no DCMotorDrive to move into the plant" in err[0]


def test_run_retry_substeps_option(tmp_path, capsys):
    """``parcosim run --retry-substeps N`` passes N to the master: a completed run lists no
    retried step; N < 2 is one line and exit 2 (the retry itself: tests/fmus/slave/test_fmu_state.py)."""
    import json

    out = tmp_path / "retry"
    assert main(["run", "thesis_sim_circle", "--retry-substeps", "4", "--out", str(out)]) == 0
    assert json.loads((out / "metrics.json").read_text())["retried_steps"] == []
    assert main(["run", "thesis_sim_circle", "--retry-substeps", "1", "--out", str(tmp_path / "x")]) == 2
    assert "retry_substeps = 1 must be an integer >= 2" in capsys.readouterr().err
