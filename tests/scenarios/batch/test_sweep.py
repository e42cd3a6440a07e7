"""Monte Carlo sweeps (scenarios.batch.sweep, perturb, engine): U = 0 is the nominal run bit for
bit, draws depend only on (seed, sample, parameter), failures are rows, an interrupted sweep
continues where it stopped, a killed worker loses no sample, the report's engine changes no
result.  One cluster of threads per module (LocalCluster start-up costs seconds); real
processes only where the point is a process: the worker killed, the CLI's scheduler."""
import math
import os
import signal

import numpy as np
import pytest

from scenarios.batch.engine import open_client
from scenarios.scenes.perturb import (ENCODER_OFFSET_SCALE, TRUNCATE_SIGMA, draw, load_perturb_file, perturbable,
                               perturbed, uncertainties)
from scenarios.run.runner import run_scene
from scenarios.scenes.catalogue import get_scene
from scenarios.batch.sweep import METRICS, read_rows, run_sweep, with_stop_time

pytestmark = [pytest.mark.slow]

SCENE = "bench_triangle_TCx"
SHORT = 0.3      # [s] of simulated time for the runs whose metrics do not matter


@pytest.fixture(scope="module")
def client():
    with open_client(workers=1, processes=False) as c:
        yield c


@pytest.fixture(scope="module")
def process_client():
    with open_client(workers=2, processes=True) as c:
        yield c


def _same(a: float, b: float) -> bool:
    """Bit-identical floats (NaN equals NaN)."""
    return np.float64(a).tobytes() == np.float64(b).tobytes()


def test_zero_uncertainty_is_the_nominal_run_bit_for_bit(client):
    """Catches a sweep that perturbs a parameter at U = 0 (a draw applied as an absolute offset) or runs
    the scene otherwise than parcosim run does."""
    sweep = run_sweep(SCENE, 1, 0.0, client=client)
    nominal = run_scene(SCENE, plots=False).metrics
    assert math.isfinite(nominal["e_ef_mm"]) and math.isfinite(nominal["e_ss_mm"])
    for row in sweep.rows:
        assert row["completed"] and row["error"] == ""
        for metric in METRICS:
            assert _same(row[metric], nominal[metric]), metric
    params = {p.name: p.nominal for p in perturbable(get_scene(SCENE))}
    assert {k: sweep.rows[0][k] for k in params} == params


def test_cli_sweep_at_zero_uncertainty_matches_cli_run(process_client, tmp_path):
    """Catches the command line's sweep running another scene setup (mode, stop time, parameters) than its
    run, or leaving out summary.md or the plot."""
    from parcosim.cli import main

    address = process_client.scheduler.address
    assert main(["sweep", SCENE, "--samples", "1", "--uncertainty", "0", "--scheduler", address,
                 "--out", str(tmp_path / "sweep")]) == 0
    assert main(["run", SCENE, "--out", str(tmp_path / "run")]) == 0
    import json

    ran = json.loads((tmp_path / "run" / "metrics.json").read_text())
    header = (tmp_path / "sweep" / "sweep.csv").read_text().splitlines()[0].split(",")
    row = read_rows(tmp_path / "sweep" / "sweep.csv", header)[0]
    for metric in METRICS:
        assert _same(row[metric], ran[metric]), metric
    assert (tmp_path / "sweep" / "summary.md").exists() and (tmp_path / "sweep" / "sweep.png").exists()


def test_draws_depend_only_on_seed_sample_and_parameter():
    """Catches draws that depend on the parameters' order or number (a shared random stream), alias across
    seed and sample, or repeat one value for all parameters."""
    params = perturbable(get_scene(SCENE))
    spread = uncertainties(params, 0.3)
    a = draw(params, spread, seed=5, sample=7)
    b = draw(params[::-1], spread, seed=5, sample=7)            # another order
    c = draw(params[:3], spread, seed=5, sample=7)              # fewer parameters
    assert a == b and all(a[k] == c[k] for k in c)
    assert draw(params, spread, seed=6, sample=7) != a and draw(params, spread, seed=5, sample=8) != a
    assert draw(params, spread, seed=6, sample=7) != draw(params, spread, seed=5, sample=8)   # no aliasing
    relative = [a[p.name] / p.nominal - 1 for p in params if not p.absolute and spread[p.name] == 0.3]
    assert len(set(relative)) == len(relative)                  # each parameter its own draw


@pytest.mark.parametrize("distribution", ["uniform", "normal"])
def test_draws_follow_the_distribution(distribution):
    """Factor 1 + u xi: uniform on [-1, 1] (std 1/sqrt 3) or normal (std ~ 1, |xi| <= 3)."""
    params = [p for p in perturbable(get_scene(SCENE)) if p.name == "drive1.R"]
    U = 0.2
    xi = np.array([(draw(params, {"drive1.R": U}, 0, i, distribution)["drive1.R"] / params[0].nominal - 1) / U
                   for i in range(3000)])
    bound = 1.0 if distribution == "uniform" else TRUNCATE_SIGMA
    assert np.all(np.abs(xi) <= bound + 1e-12)
    expected = 1 / math.sqrt(3) if distribution == "uniform" else 0.986   # N(0,1) truncated at 3
    assert abs(np.mean(xi)) < 0.05 and abs(np.std(xi) - expected) < 0.03


def test_weights_and_overrides(tmp_path):
    """Catches uncertainty weights or per-parameter overrides that do not reach the spread."""
    params = perturbable(get_scene(SCENE))
    spread = uncertainties(params, 0.2)
    assert spread["plant.chain1_m2"] == 0.2 and spread["drive2.kt"] == 0.2
    assert spread["plant.encoder_offset1"] == pytest.approx(0.2 * ENCODER_OFFSET_SCALE)
    f = tmp_path / "p.toml"
    f.write_text('distribution = "normal"\n[uncertainty]\n"drive*.mu" = 0.5\n"plant.chain1_m2" = 0\n')
    spec = load_perturb_file(f)
    spread = uncertainties(params, 0.2, spec["uncertainty"])
    assert spec["distribution"] == "normal" and spread["drive1.mu"] == spread["drive2.mu"] == 0.5
    assert draw(params, spread, 0, 3)["plant.chain1_m2"] == 0.124
    f.write_text('[uncertainty]\n"drive3.R" = 0.1\n')
    with pytest.raises(ValueError, match="'drive3.R' matches no parameter"):
        uncertainties(params, 0.2, load_perturb_file(f)["uncertainty"])
    f.write_text('[uncertainty]\n"drive1.R" = -1\n')
    with pytest.raises(ValueError, match="uncertainty 'drive1.R' = -1 must be"):
        load_perturb_file(f)


def test_controller_side_keeps_the_nominal_model():
    """Catches a perturbation that leaks into the controller's model (it must stay nominal)."""
    scene = get_scene(SCENE)
    params = perturbable(scene)
    values = draw(params, uncertainties(params, 0.4), 0, 0)
    changed = perturbed(scene, params, values)
    for name in ("ctrl", "deriv", "obs1", "obs2", "traj"):
        assert changed.system.component(name) == scene.system.component(name)
    drive = changed.system.component("drive1").parameters
    nominal = {p.name: p.nominal for p in params}
    assert drive["R"] == values["drive1.R"] != nominal["drive1.R"]
    assert drive["R_design"] == nominal["drive1.R"] and drive["kt_design"] == nominal["drive1.kt"]


def _drive(**parameters):
    from fmus.cosim.backends import InProcessInstance

    instance = InProcessInstance("DCMotorDrive", "drive")
    instance.enter_initialization({"preset": "motor1", **parameters}, 0.0)
    instance.exit_initialization()
    return instance.slave.drive


def test_design_parameters_keep_the_current_controller():
    """Catches a perturbed drive whose current controller is redesigned from the perturbed motor."""
    from motor import motor1

    coefficients = lambda d: (d.alpha, d.beta, d.gamma, d.delta)   # noqa: E731
    nominal = coefficients(_drive().controller.design)
    off = dict(R=1.3 * motor1.R, L=0.8 * motor1.L, kt=1.1 * motor1.kt, ke=0.9 * motor1.ke, b=1.2 * motor1.b)
    assert coefficients(_drive(**off).controller.design) != nominal            # retuned to the changed motor
    kept = _drive(**off, R_design=motor1.R, L_design=motor1.L, kt_design=motor1.kt, ke_design=motor1.ke,
                  b_design=motor1.b)
    assert coefficients(kept.controller.design) == nominal
    assert kept.params.R == off["R"]                                        # the physics is the changed motor
    from fmus.cosim.backends import InProcessInstance

    bad = InProcessInstance("DCMotorDrive", "drive")
    bad.enter_initialization({"L_design": -2.0}, 0.0)
    bad.exit_initialization()
    assert "parameter L_design = -2.0 must be > 0" in bad.slave.error


def test_encoder_offset_shifts_the_reading_by_whole_counts():
    """Catches an encoder offset applied to the true angle (moving the mechanism) or by a fraction of a
    count."""
    from plant import PlantSimulator, get_preset

    params = get_preset("bench")
    plain = PlantSimulator(params, -0.002, 0.108)
    count = plain.count
    shifted = PlantSimulator(params, -0.002, 0.108, encoder_offsets=(3 * count, -5 * count))
    for sim in (plain, shifted):
        sim.step(0.05, -0.02, 1e-3)
    a, b = plain.outputs(), shifted.outputs()
    assert a["q1"] == b["q1"] and a["x"] == b["x"]
    assert round((b["q1_enc"] - a["q1_enc"]) / count) == 3 and round((b["q2_enc"] - a["q2_enc"]) / count) == -5


def test_chain_parameters_reach_the_plant():
    """Catches perturbed chain parameters that do not reach the plant's model."""
    from fmus.cosim.backends import InProcessInstance

    plant = InProcessInstance("FiveBarPlant", "plant")
    plant.enter_initialization({"preset": "bench", "x0": -0.002, "y0": 0.108, "chain2_m2": 0.2,
                                "chain1_l1": 0.121}, 0.0)
    plant.exit_initialization()
    p = plant.slave.sim.params
    assert p.chain2.m2 == 0.2 and p.chain1.l1 == 0.121 and p.chain1.m2 == 0.124
    bad = InProcessInstance("FiveBarPlant", "plant")
    bad.enter_initialization({"preset": "bench", "chain1_l2": 0.0}, 0.0)
    bad.exit_initialization()
    assert "parameter chain1_l2 = 0.0 must be > 0" in bad.slave.error


def test_a_failing_run_is_a_row_with_its_error(client):
    """Catches a refused sample dropped from the rows, marked completed, given no error naming the
    parameter, or miscounted in the summary."""
    scene = with_stop_time(get_scene(SCENE), SHORT)
    params = perturbable(scene)
    spec = {"uncertainty": {"drive1.R": 5.0}}          # factor 1 + 5 xi: negative for xi < -0.2
    spread = uncertainties(params, 0.0, spec["uncertainty"])
    negative = [draw(params, spread, 0, i)["drive1.R"] < 0 for i in range(4)]
    assert any(negative) and not all(negative), "precondition: both kinds among the samples"
    sweep = run_sweep(scene, 4, 0.0, perturb=spec, client=client)
    for row, bad in zip(sweep.rows, negative):
        assert row["completed"] is (not bad)
        assert ("R = " in row["error"]) is bad
    assert sweep.summary["failed"] == sum(negative)


def test_an_interrupted_sweep_computes_only_what_is_missing(client, tmp_path):
    """Catches a resumed sweep that recomputes done samples, keeps a torn row, rewrites the file's good
    rows, gives other values than a fresh sweep, or resumes with another seed."""
    out = tmp_path / "s"
    first = run_sweep(SCENE, 3, 0.3, stop_time=SHORT, out_dir=out, client=client, plots=False)
    assert first.computed == [0, 1, 2]
    csv = out / "sweep.csv"
    whole = csv.read_bytes()
    with open(csv, "ab") as f:            # a row torn by a killed process
        f.write(b"3,0.0499,0.12")
    torn = csv.read_bytes()
    header = whole.decode().splitlines()[0].split(",")
    assert len(read_rows(csv, header)) == 3 and csv.read_bytes() == torn   # a reader leaves the file alone
    second = run_sweep(SCENE, 5, 0.3, stop_time=SHORT, out_dir=out, client=client, plots=False)
    assert second.computed == [3, 4]
    assert csv.read_bytes().startswith(whole) and csv.read_text().count("\n") == 6
    on_disk = sorted(read_rows(csv, header), key=lambda r: r["sample"])
    assert [r["sample"] for r in on_disk] == [0, 1, 2, 3, 4]
    assert all(_same(a[k], b[k]) for a, b in zip(on_disk, second.rows) for k in second.parameters + list(METRICS))
    fresh = run_sweep(SCENE, 5, 0.3, stop_time=SHORT, out_dir=tmp_path / "fresh", client=client, plots=False)
    for a, b in zip(second.rows, fresh.rows):
        assert all(_same(a[k], b[k]) for k in second.parameters + list(METRICS))
        assert a["completed"] == b["completed"]
    assert run_sweep(SCENE, 5, 0.3, stop_time=SHORT, out_dir=out, client=client, plots=False).computed == []
    with pytest.raises(ValueError, match="seed = 0, not 1"):
        run_sweep(SCENE, 5, 0.3, seed=1, stop_time=SHORT, out_dir=out, client=client)


def test_a_killed_worker_loses_no_sample(process_client, client):
    """SIGKILL a worker process while it runs a sample: the scheduler reruns its tasks."""
    scene = with_stop_time(get_scene(SCENE), 1.5)
    pids = process_client.run(os.getpid)
    killed = []

    def kill_a_busy_worker(row):
        if killed:
            return
        busy = [w for w, keys in process_client.processing().items() if keys]
        assert busy, "precondition: a worker is running a sample"
        os.kill(pids[busy[0]], signal.SIGKILL)
        killed.append(busy[0])

    sweep = run_sweep(scene, 6, 0.3, client=process_client, on_row=kill_a_busy_worker)
    assert killed
    assert all(r["completed"] and r["error"] == "" for r in sweep.rows), [r["error"] for r in sweep.rows]
    reference = run_sweep(scene, 6, 0.3, client=client)
    for a, b in zip(sweep.rows, reference.rows):
        assert all(_same(a[m], b[m]) for m in METRICS)


def test_report_engine_gives_the_serial_results(client, tmp_path):
    """Catches the Dask engine's report running a scene otherwise than the serial run (other metrics) or
    not writing each scene's files."""
    from scenarios.batch.report import run_bench

    names = ["bench_circle_TCMDx", "bench_triangle_PDMDq"]
    engine = run_bench(tmp_path, scenes=names, client=client)
    assert list(engine) == names
    for name in names:
        serial = run_scene(name, plots=False).metrics
        for key in ("e_ef_mm", "tau_ef_Nm", "e_ss_mm", "e_ss_x_mm", "e_ss_y_mm", "e_max_mm", "simulated_s"):
            assert _same(engine[name][key], serial[key]), (name, key)
        assert (tmp_path / name / "result.csv").exists() and (tmp_path / name / "path.png").exists()


def _lugre_scene():
    from scenarios.scenes.thesis import Fidelity, bench

    return with_stop_time(bench("TCx", "triangle", fidelity=Fidelity(friction="lugre")), SHORT)


def test_a_lugre_drive_s_break_away_follows_its_coulomb_torque():
    """mu_s is a parameter of LuGre drives only; without an uncertainty of its own it takes
    mu's relative change, so every sample keeps the preset's ratio mu_s/mu (1.25)."""
    from motor import get_motor_preset

    assert not any(p.name.endswith(".mu_s") for p in perturbable(get_scene(SCENE)))      # tanh drives
    params = perturbable(_lugre_scene())
    spread = uncertainties(params, 0.3)
    assert spread["drive1.mu"] == 0.3 and spread["drive1.mu_s"] is None
    for j in (1, 2):
        preset = get_motor_preset(f"motor{j}")
        for i in range(20):
            v = draw(params, spread, 0, i)
            assert v[f"drive{j}.mu_s"] / v[f"drive{j}.mu"] == pytest.approx(preset.mu_s / preset.mu, rel=1e-15)
    own = uncertainties(params, 0.3, {"drive1.mu_s": 0.0})          # the user's mu_s: held
    assert all(draw(params, own, 0, i)["drive1.mu_s"] == get_motor_preset("motor1").mu_s for i in range(5))
    with pytest.raises(ValueError, match="drive1.mu_s follows 'drive1.mu', which is not drawn with it"):
        draw([p for p in params if p.name != "drive1.mu"], spread, 0, 0)


def test_a_lugre_sample_with_mu_past_the_preset_s_break_away_runs(client):
    """A sample whose mu is drawn 27 % or more above the preset's (past the preset's mu_s =
    1.25 mu) runs, with mu_s scaled by the same factor; the same sample with mu_s held by the
    user (its own uncertainty 0) has mu > mu_s, which the drive refuses naming both."""
    from motor import motor1

    scene = _lugre_scene()
    params = perturbable(scene)
    ours = {"uncertainty": {"drive1.mu": 0.3}}
    spread = uncertainties(params, 0.0, ours["uncertainty"])
    seed = next(s for s in range(200) if draw(params, spread, s, 0)["drive1.mu"] > 1.27 * motor1.mu)
    row = run_sweep(scene, 1, 0.0, seed=seed, perturb=ours, client=client).rows[0]
    assert row["completed"], row["error"]
    assert row["drive1.mu"] > 1.27 * motor1.mu > motor1.mu_s
    assert row["drive1.mu_s"] / row["drive1.mu"] == pytest.approx(motor1.mu_s / motor1.mu, rel=1e-15)
    held = {"uncertainty": {"drive1.mu": 0.3, "drive1.mu_s": 0.0}}
    row = run_sweep(scene, 1, 0.0, seed=seed, perturb=held, client=client).rows[0]
    assert not row["completed"] and row["drive1.mu_s"] == motor1.mu_s
    assert "break-away torque Fs (mu_s)" in row["error"] and "Coulomb torque Fc (mu)" in row["error"], row["error"]


def test_worker_processes_import_the_installed_code_not_an_fmus_copy_on_the_parents_path(tmp_path, monkeypatch):
    """A parent that ran a pythonfmu FMU in process has the FMU's resources folder on its path,
    with a partial copy of ``fmus``; each worker process drops it before anything of ours is
    imported (scenarios/batch/worker_path.py).  Wrong code it catches: a preload given by module
    name, whose import of the ``scenarios`` package imports ``fmus`` from that copy first (the
    sweeps' workers then failed with "No module named 'fmus.slave.identity'")."""
    import fmus

    fmu = tmp_path / "extracted"
    (fmu / "resources" / "fmus").mkdir(parents=True)
    (fmu / "resources" / "fmus" / "__init__.py").write_text("raise ImportError('the FMU copy of fmus was imported')\n")
    (fmu / "modelDescription.xml").write_text("<fmiModelDescription/>\n")
    monkeypatch.syspath_prepend(str(fmu / "resources"))
    with open_client(workers=1, processes=True) as c:
        found = c.run(lambda: __import__("fmus").__file__)
    assert list(found.values()) == [fmus.__file__]
