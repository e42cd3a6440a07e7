"""scenarios/studies/pendulum_trade.py's study functions without their long runs (run_scene
replaced by one that records each scene and gives made-up columns whose deviations are known
in closed form): the fidelity table's settings and its RMS deviations from the 32-substep run,
the seed-vs-exact comparison's gaps, the files ``run_pendulum_trade`` writes (read back
exactly) and the figures' lines (read back from the drawn figures).  Issue 31: results against
an independent computation, every written value read back, an option (``quick``) taking effect."""
from __future__ import annotations

import csv
import math
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

from scenarios.studies import pendulum_trade

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

#: The truth's (first run's) columns: 6 rows; each later run has 5 (a shorter run is compared
#: on its own rows).
T = np.arange(6) * 0.25
TRUTH = {"t": T, "psi": np.radians([1.0, -2.0, 0.5, 0.25, 3.0, -1.0]), "x": 0.1 * T, "y": -0.2 * T ** 2}
SIGNS = np.array([1.0, -1.0, 1.0, -1.0, 1.0])


@pytest.fixture
def study(monkeypatch):
    """run_scene: call k (0: the truth) records the scene, advances a fake clock by k s and
    returns columns whose pitch is k/2 deg and whose axle is 5 k mm off the truth's (RMS)."""
    asked, clock = [], [100.0]

    def run_scene(scene):
        k = len(asked)
        asked.append(scene)
        clock[0] += k
        if k == 0:
            return SimpleNamespace(columns=dict(TRUTH), metrics={"completed": True, "last_second_pitch_deg": 0.0,
                                                                 "energy_J": 0.0})
        columns = {"t": T[:5], "psi": TRUTH["psi"][:5] + math.radians(0.5 * k) * SIGNS,
                   "x": TRUTH["x"][:5] + 3e-3 * k * SIGNS, "y": TRUTH["y"][:5] - 4e-3 * k}
        metrics = {"completed": k != 3, "last_second_pitch_deg": 0.125 * k}
        if k != 5:
            metrics["energy_J"] = 2.0 ** -k
        return SimpleNamespace(columns=columns, metrics=metrics)

    monkeypatch.setattr(pendulum_trade, "run_scene", run_scene)
    monkeypatch.setattr(pendulum_trade, "time", SimpleNamespace(perf_counter=lambda: clock[0]))
    return asked


def _plant(scene):
    return scene.system.component("plant").parameters


def test_the_fidelity_rows_change_one_setting_each_and_deviate_from_the_32_substep_run(study):
    """Each row's scene is the default but for its one setting; the truth is the default at 32
    RK4 substeps; the deviations are RMS over the run's own rows, the pitch in degrees and the
    axle in mm, the wall time the run's alone.  Catches a setting applied to another row or not
    at all, the truth at other substeps, a deviation of x alone or not squared, radians for
    degrees, a missing metric not NaN, and the wall time of another run."""
    rows = pendulum_trade.fidelity_rows("pendulum_push", 0.75)
    truth, *runs = study
    assert _plant(truth)["substeps"] == 32
    for scene in study:
        assert scene.name == "pendulum_push" and scene.system.stop_time == 0.75 and scene.window == (0.0, 0.75)
    labels = ["defaults", "yaw off", "ideal electrics", "friction off", "seed model", "plant substeps 1",
              "plant substeps 8"]
    assert [r["setting"] for r in rows] == labels
    default = pendulum_trade.pendulum_scene("pendulum_push").system
    names = {c.name for c in default.components}
    for label, scene in zip(labels, runs):
        plant, ctrl = _plant(scene), scene.system.component("ctrl").parameters
        assert plant.get("substeps", default.component("plant").parameters.get("substeps")) == \
            {"plant substeps 1": 1, "plant substeps 8": 8}.get(label, default.component("plant").parameters.get(
                "substeps"))
        assert (plant["yaw"], ctrl["yaw"]) == ((False, False) if label == "yaw off" else (True, True))
        assert plant["model"] == ("seed" if label == "seed model" else "exact")
        drives = {c.name for c in scene.system.components} - {"ctrl", "plant"}
        assert drives == (set() if label == "ideal electrics" else names - {"ctrl", "plant"})
        if label != "ideal electrics":
            assert {scene.system.component(d).parameters.get("b") for d in drives} == \
                ({0.0} if label == "friction off" else {None})
    for k, row in enumerate(rows, start=1):
        assert row["wall_s"] == k and row["completed"] is (k != 3)
        assert row["rms_psi_deg"] == pytest.approx(0.5 * k, rel=1e-12)
        assert row["rms_axle_mm"] == pytest.approx(5.0 * k, rel=1e-12)
        assert row["last_second_pitch_deg"] == 0.125 * k
        assert row["energy_J"] == 2.0 ** -k if k != 5 else math.isnan(row["energy_J"])


def test_without_a_stop_the_fidelity_rows_run_the_whole_scene(study):
    """Catches the scenes shortened (or their window changed) when no stop is asked for."""
    pendulum_trade.fidelity_rows("pendulum_balance")
    whole = pendulum_trade.pendulum_scene("pendulum_balance")
    assert all(s.system.stop_time == whole.system.stop_time and s.window == whole.window for s in study)


def _read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_the_quick_trade_writes_the_fidelity_table_as_csv_and_markdown(study, tmp_path):
    """``quick``: the fidelity table of 1 s runs only (no sweeps); trade.csv holds each row's
    values exactly (floats as repr), trade.md the title with --quick and the table.  Catches
    the csv written elsewhere or missing a row or column, quick running the sweeps or the
    whole scene, and the title or a section lost; the folder made without its missing parent
    (sibling of seed 4201 [196])."""
    tmp_path = tmp_path / "new"
    said = []
    report = pendulum_trade.run_pendulum_trade("pendulum_drive", quick=True, out_dir=tmp_path / "t",
                                               progress=said.append)
    assert list(report) == ["fidelity"] and said == ["pendulum_drive: fidelity settings ..."]
    assert {s.system.stop_time for s in study} == {1.0} and {s.name for s in study} == {"pendulum_drive"}
    rows = report["fidelity"]
    back = _read_csv(tmp_path / "t" / "trade.csv")
    assert [list(r) for r in back] == [list(rows[0])] * len(rows)
    for row, read in zip(rows, back):
        for key, value in row.items():
            assert read[key] == str(value)
            if isinstance(value, float) and not math.isnan(value):
                assert float(read[key]) == value
    assert (tmp_path / "t" / "trade.md").read_text() == \
        f"# parcosim trade pendulum_drive --quick\n\n## fidelity\n\n{pendulum_trade.markdown(rows)}\n"


def test_the_full_trade_adds_the_sweeps_in_order(study, tmp_path, monkeypatch):
    """Catches the sweeps left out of the full study or of trade.md, or quick's title on it."""
    monkeypatch.setattr(pendulum_trade, "sample_time_rows", lambda: [{"T_ms": 2.0, "balanced": True}])
    monkeypatch.setattr(pendulum_trade, "battery_rows", lambda: [{"v_battery": 1.5, "balanced": False}])
    said = []
    report = pendulum_trade.run_pendulum_trade(out_dir=tmp_path, progress=said.append)
    assert list(report) == ["fidelity", "sample_time", "battery"]
    assert said == ["pendulum_balance: fidelity settings ...", "sample times ...", "battery voltages ..."]
    whole = pendulum_trade.pendulum_scene("pendulum_balance").system.stop_time
    assert {s.system.stop_time for s in study} == {whole}
    text = "\n\n".join(f"## {part}\n\n{pendulum_trade.markdown(rows)}" for part, rows in report.items())
    assert (tmp_path / "trade.md").read_text() == f"# parcosim trade pendulum_balance\n\n{text}\n"
    assert len(_read_csv(tmp_path / "trade.csv")) == len(report["fidelity"])


def _drive_runs(monkeypatch):
    """run_scene for pendulum_drive: the seed model's run off the exact one's by known gaps."""
    t = np.arange(0.0, 10.001, 0.5)
    asked = []

    def run_scene(scene):
        asked.append(scene)
        seed = _plant(scene)["model"] == "seed"
        x, y = 0.1 * t, 0.01 * t ** 2
        psi = np.radians(0.2 * np.sin(t))
        if seed:       # axle 5 mm off at t = 3 s (the largest); pitch off 0.3 deg at 7 s (the largest while
            # turning, 6-8 s), 0.25 at 6 and 8 s, 0.5 at 5.5 s and 0.7 at 8.5 s (outside), 0.6 at 2 s
            x, y = x + 3e-3 * (t == 3.0), y - 4e-3 * (t == 3.0)
            psi = psi + np.radians(0.3) * (t == 7.0) + np.radians(0.25) * ((t == 6.0) | (t == 8.0))
            psi = psi - np.radians(0.5) * (t == 5.5) + np.radians(0.7) * (t == 8.5) - np.radians(0.6) * (t == 2.0)
        columns = {"t": t, "x": x, "y": y, "psi": psi, "x_d": 0.1 * t, "y_d": np.zeros_like(t)}
        return SimpleNamespace(columns=columns, metrics={"final_position_error_mm": 1.5 if seed else 0.25})

    monkeypatch.setattr(pendulum_trade, "run_scene", run_scene)
    return asked


def test_the_drive_comparison_measures_the_seed_models_gaps_from_the_exact_one(monkeypatch):
    """Catches the axle gap of one coordinate or a sum, the pitch gaps not in degrees or the
    turning window's (6-8 s) not restricted to it, the runs' models swapped, and the open
    loop's accelerations of other states or another sign."""
    from plant.wheeled import WheeledPendulum
    from plant.wheeled_kernel import STATE

    asked = _drive_runs(monkeypatch)
    out = pendulum_trade.drive_comparison()
    assert [(s.name, _plant(s)["model"]) for s in asked] == [("pendulum_drive", "exact"), ("pendulum_drive", "seed")]
    assert out["max_axle_gap_mm"] == pytest.approx(5.0, rel=1e-12)
    assert out["max_pitch_gap_deg"] == pytest.approx(0.7, rel=1e-12)
    assert out["max_pitch_gap_turning_deg"] == pytest.approx(0.3, rel=1e-12)
    assert out["final_position_error_mm"] == {"exact": 0.25, "seed": 1.5}
    assert list(out["runs"]) == ["exact", "seed"]
    y = np.zeros(len(STATE))
    for name, value in (("psi", math.radians(5.0)), ("dtheta", 10.0), ("dphi", 2.0)):
        y[STATE[name].start] = value
    names = ("ddtheta", "ddpsi", "ddphi")
    exact, seed = ({n: float(WheeledPendulum(model=m).derivative(y)[STATE[n[1:]].start]) for n in names} for m in ("exact", "seed"))
    assert out["open_loop_accelerations_exact"] == exact
    assert out["open_loop_acceleration_gap"] == {n: exact[n] - seed[n] for n in names}
    assert any(abs(v) > 0.0 for v in out["open_loop_acceleration_gap"].values())


def test_the_figures_draw_the_sweeps_and_the_two_models_paths_and_gap(monkeypatch, tmp_path):
    """Reads the drawn lines and axes back.  Catches a sweep's x or y of another column, a fallen
    run drawn (instead of marked), the band's line elsewhere, the reference or a model's path
    not drawn, the gap of one coordinate or not in mm, and a panel's labels, scale, equal
    aspect or the path's y range lost."""
    _drive_runs(monkeypatch)
    comparison = pendulum_trade.drive_comparison()
    kept = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    samples = [{"T_ms": 1.0, "completed": True, "last_second_pitch_deg": 0.01},
               {"T_ms": 4.0, "completed": True, "last_second_pitch_deg": 0.0},
               {"T_ms": 8.0, "completed": False, "last_second_pitch_deg": 3.0}]
    battery = [{"v_battery": 8.0, "completed": True, "last_second_pitch_deg": 0.05},
               {"v_battery": 1.0, "completed": False, "last_second_pitch_deg": 9.0}]
    files = pendulum_trade.plot(samples, battery, comparison, tmp_path)
    assert files == [tmp_path / "pendulum_sweeps.png", tmp_path / "pendulum_drive.png"]
    assert all(f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for f in files)
    sweeps, drive = kept
    assert [(ax.get_xlabel(), ax.get_ylabel(), ax.get_title(), ax.get_yscale()) for ax in sweeps.axes] == [
        ("sample time T [ms]", "deg", "pendulum_balance (red: fell)", "log"),
        ("battery voltage [V]", "deg", "pendulum_balance (red: fell)", "log")]
    assert [(ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) for ax in drive.axes] == [
        ("x [m]", "y [m]", "pendulum_drive: axle path"), ("t [s]", "psi [deg]", "pitch"),
        ("t [s]", "mm", "exact vs seed model")]
    assert drive.axes[0].get_aspect() == 1.0 and drive.axes[0].get_ylim() == (-0.3, 0.3)
    for ax in (*sweeps.axes, *drive.axes):
        assert ax.get_legend() is not None
    for ax, rows, key in zip(sweeps.axes, (samples, battery), ("T_ms", "v_battery")):
        data, *marks = ax.get_lines()
        assert list(data.get_xdata()) == [r[key] for r in rows]
        expected = [max(r["last_second_pitch_deg"], 1e-4) if r["completed"] else np.nan for r in rows]
        np.testing.assert_array_equal(data.get_ydata(), expected)
        fell = [r[key] for r in rows if not r["completed"]]
        assert [m.get_xdata()[0] for m in marks[:-1]] == fell
        assert list(marks[-1].get_ydata()) == [pendulum_trade.BALANCED_DEG] * 2
    path, pitch, gap = drive.axes
    c, s = (comparison["runs"][m].columns for m in ("exact", "seed"))
    drawn = {line.get_label(): line for line in path.get_lines()}
    for label, cols in (("exact", c), ("seed", s)):
        np.testing.assert_array_equal(drawn[label].get_xdata(), cols["x"])
        np.testing.assert_array_equal(drawn[label].get_ydata(), cols["y"])
        np.testing.assert_array_equal({l.get_label(): l for l in pitch.get_lines()}[label].get_ydata(),
                                      np.degrees(cols["psi"]))
    np.testing.assert_array_equal(drawn["reference"].get_xdata(), c["x_d"])
    np.testing.assert_array_equal(drawn["reference"].get_ydata(), c["y_d"])
    (line,) = gap.get_lines()
    assert float(np.max(line.get_ydata())) == pytest.approx(5.0, rel=1e-12)
    np.testing.assert_allclose(line.get_ydata(), 1e3 * np.hypot(c["x"] - s["x"], c["y"] - s["y"]), rtol=0, atol=0)


def test_the_command_line_runs_the_study_and_with_docs_draws_its_sweeps(monkeypatch, tmp_path, capsys):
    """``main``: ``--quick`` and ``--out`` reach the study; each part's table is printed; the full
    study adds the drive comparison, and ``--docs`` draws the figures into docs/ from the study's
    own sweeps (the sample-time panel from the sample-time rows, the battery panel from the
    battery rows).  Catches an option not taking effect, the sweeps given to the figure swapped,
    the figures drawn without ``--docs`` or the comparison run in a quick study."""
    _drive_runs(monkeypatch)
    samples = [{"T_ms": 1.0, "completed": True, "last_second_pitch_deg": 0.01},
               {"T_ms": 8.0, "completed": False, "last_second_pitch_deg": 3.0}]
    battery = [{"v_battery": 8.0, "completed": True, "last_second_pitch_deg": 0.05},
               {"v_battery": 4.0, "completed": True, "last_second_pitch_deg": 0.5}]
    calls = []

    def study(quick, out_dir, progress):
        calls.append((quick, out_dir))
        report = {"fidelity": [{"setting": "x", "rms": 1.0}]}
        return report if quick else {**report, "sample_time": samples, "battery": battery}

    monkeypatch.setattr(pendulum_trade, "run_pendulum_trade", study)
    monkeypatch.setattr(pendulum_trade, "DOCS", tmp_path)
    kept = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    pendulum_trade.main(["--quick", "--out", str(tmp_path / "q"), "--docs"])
    assert calls == [(True, str(tmp_path / "q"))] and not kept and not list(tmp_path.glob("*.png"))
    assert f"\nfidelity\n{pendulum_trade.markdown([{'setting': 'x', 'rms': 1.0}])}\n" in capsys.readouterr().out
    pendulum_trade.main(["--out", str(tmp_path / "full")])
    assert calls[-1] == (False, str(tmp_path / "full")) and not kept
    assert "'max_axle_gap_mm': 5.0" in capsys.readouterr().out
    pendulum_trade.main(["--docs"])
    assert calls[-1] == (False, "out/pendulum_trade")
    assert {p.name for p in tmp_path.glob("*.png")} == {"pendulum_sweeps.png", "pendulum_drive.png"}
    sweeps = kept[0]
    for ax, rows, key in zip(sweeps.axes, (samples, battery), ("T_ms", "v_battery")):
        assert list(ax.get_lines()[0].get_xdata()) == [r[key] for r in rows]
    out = capsys.readouterr().out
    assert f"\nbattery\n{pendulum_trade.markdown(battery)}\n" in out and str(tmp_path / "pendulum_drive.png") in out
