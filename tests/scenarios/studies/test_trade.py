"""``parcosim trade``: the quick sweep runs, writes its files, and its rows mean what they say."""
import csv
import math

import pytest

from scenarios.studies.trade import COLUMNS, Trade, pareto, run_trade


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    """The quick sweep of the default scene, run once (~10-20 s)."""
    out = tmp_path_factory.mktemp("trade")
    return run_trade(quick=True, out_dir=out), out


def _csv_rows(out):
    with open(out / "trade.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_quick_sweep_writes_csv_markdown_and_plot(quick):
    """Catches the trade study writing a file empty or missing, a setting twice, no defaults row, or a
    table that does not name its plot and command."""
    trade, out = quick
    assert isinstance(trade, Trade) and trade.scene == "bench_circle_TCMDx" and trade.stop_time == 1.0
    for name in ("trade.csv", "trade.md", "trade.png"):
        assert (out / name).stat().st_size > 0
    rows = _csv_rows(out)
    assert set(COLUMNS) <= set(rows[0]) and {"setting", "wall_s", "rms_err_m", "max_err_m"} <= set(rows[0])
    assert len(rows) == len(trade.rows) == len({r["setting"] for r in rows})
    assert [r for r in rows if r["setting"] == "defaults"]
    text = (out / "trade.md").read_text()
    assert "| defaults | accuracy |" in text and "trade.png" in text and "--quick" in text


def test_every_run_completed_with_finite_positive_errors(quick):
    """Catches a setting whose run stopped or whose error against the reference is zero, NaN or an RMS
    above its maximum (a reference compared with itself, rows misaligned)."""
    trade, _ = quick
    for r in trade.rows:
        assert not r["error"], (r["setting"], r["error"])
        for key in ("wall_s", "rms_err_m", "max_err_m"):
            assert math.isfinite(r[key]) and r[key] > 0.0, (r["setting"], key, r[key])
        assert r["rms_err_m"] <= r["max_err_m"]
        assert r["kind"] in ("accuracy", "fidelity")


def test_defaults_are_the_scale(quick):
    """Catches speed-up and gain not measured against the defaults' row."""
    trade, _ = quick
    base = trade.row("defaults")
    assert base["speedup"] == 1.0 and base["gain"] == 1.0
    # the defaults' deviation is the drive/plant coupling's, ~1e-5 m (docs/reference.md), not zero
    assert 1e-7 < base["rms_err_m"] < 1e-4


def test_a_tighter_plant_is_not_worse(quick):
    """RK4 x4 cuts the plant's own error (~1e-11 m) and nothing else: the deviation, set by the
    drive/plant coupling, stays (within 1e-9 m), and the loop-closure residual falls."""
    trade, _ = quick
    base, tight = trade.row("defaults"), trade.row("plant rk4 substeps=4")
    assert tight["rms_err_m"] <= base["rms_err_m"] + 1e-9
    assert tight["max_err_m"] <= base["max_err_m"] + 1e-9
    assert tight["residual_m"] < base["residual_m"]


def test_drive_columns_only_where_there_are_drives(quick):
    """Catches drive current and energy errors computed for a scene without drives (from columns that are
    not there) or missing where there are drives."""
    trade, _ = quick
    base, ideal = trade.row("defaults"), trade.row("ideal actuators")
    assert math.isfinite(base["current_err_A"]) and base["current_err_A"] > 0.0
    assert math.isfinite(base["energy_err"])
    assert not math.isfinite(ideal["current_err_A"]) and not math.isfinite(ideal["energy_err"])
    assert ideal["kind"] == "fidelity"


def test_fidelity_rows_are_never_on_the_front(quick):
    """Catches a Pareto front that admits settings which change the model (fidelity), or misses the most
    accurate setting."""
    trade, _ = quick
    front = [r for r in trade.rows if r["pareto"]]
    assert front and all(r["kind"] == "accuracy" for r in front)
    accuracy = [r for r in trade.rows if r["kind"] == "accuracy"]
    # nothing beats the most accurate setting: its accuracy is on the front by construction
    assert min(r["rms_err_m"] for r in front) == min(r["rms_err_m"] for r in accuracy)


def _row(name, wall, err, kind="accuracy"):
    return {"setting": name, "kind": kind, "wall_s": wall, "rms_err_m": err, "error": ""}


def test_pareto_front():
    """Catches a Pareto front that keeps a dominated row, drops a front row, or takes a failed run."""
    rows = [_row("a", 1.0, 1e-5), _row("b", 2.0, 1e-6), _row("c", 2.5, 2e-6), _row("d", 0.5, 1e-3),
            _row("e", 0.1, 1e-9, kind="fidelity"), _row("f", 1.05, 9e-6), _row("g", 4.0, 1e-7)]
    rows.append({**_row("h", 0.01, 1e-12), "error": "plant refused the step"})
    names = [rows[i]["setting"] for i in pareto(rows, wall_tolerance=0.0)]
    assert names == ["d", "a", "f", "b", "g"]
    # within 10 % of a's wall time, f is as fast and more accurate: a leaves the front
    assert [rows[i]["setting"] for i in pareto(rows, wall_tolerance=0.10)] == ["d", "f", "b", "g"]


def test_cli_refuses_an_unknown_scene(capsys):
    """Catches parcosim trade starting its runs (or tracing back) for a scene that does not exist."""
    from parcosim.cli import main

    assert main(["trade", "no_such_scene", "--quick", "--out", "unused"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown scene 'no_such_scene'" in err[0]


def test_drives_in_plant_is_the_accurate_end_of_the_front(quick):
    """The drives integrated in the plant remove the coupling error: ≥ 100× the defaults'
    accuracy (docs/trade.md: 2.2e4× over 9 s), with no encoder reading that differs from the
    reference's and its currents within 1e-3 A."""
    trade, _ = quick
    row = trade.row("drives in plant, substeps=8")
    assert row["gain"] >= 100.0 and row["enc_diff"] == 0 and row["current_err_A"] < 1e-3
    assert row["pareto"]


class _Run:
    def __init__(self, time, x):
        import numpy as np

        self.time = np.asarray(time, dtype=float)
        self.signals = {"plant.x": np.asarray(x, dtype=float), "plant.y": np.zeros(len(time))}

    def __getitem__(self, signal):
        return self.signals[signal]


def test_a_run_at_a_longer_step_meets_every_kth_reference_row():
    """Catches the comparison of a 2 ms run with the 1 ms reference by exact time equality (t += h drifts,
    no row would match) or at the wrong rows."""
    from scenarios.reference import common_rows, deviation

    reference = _Run([k * 1e-3 for k in range(11)], [k * 1e-3 for k in range(11)])
    t2 = [0.0]
    for _ in range(5):
        t2.append(t2[-1] + 2e-3)              # the master's t += h
    run = _Run(t2, [2 * k * 1e-3 for k in range(6)])
    ia, ib = common_rows(run.time, reference.time)
    assert list(ia) == [0, 1, 2, 3, 4, 5] and list(ib) == [0, 2, 4, 6, 8, 10]
    assert deviation(run, reference) == {"rms": 0.0, "max": 0.0, "t_max": 0.0, "rows": 6}
    run.signals["plant.x"][3] += 1e-6
    d = deviation(run, reference)
    assert d["max"] == pytest.approx(1e-6) and d["t_max"] == pytest.approx(6e-3) and d["rows"] == 6
