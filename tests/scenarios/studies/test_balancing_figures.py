"""scenarios/studies/balancing.py's figures and its command line without its long runs (``measure``
replaced by one returning made-up rows and columns): every plotted line's data read back from
the figure exactly (the path in mm, the torques and currents against time, each sweep curve
against the rows it comes from), the scenes' table and ``main``'s files (issue 31: seed 3501's
survivor [18], the path plotted in metres on the mm axes; every exported value read back)."""
from __future__ import annotations

import csv

import matplotlib
import numpy as np
import pytest

from scenarios.studies import balancing

matplotlib.use("Agg")


def _columns(balanced: bool) -> dict:
    t = np.arange(101) * 2e-3
    k = 2.0 if balanced else 1.0
    return {"t": t, "x": 0.05 * k * np.cos(t) + 0.01, "y": 0.2 + 0.05 * np.sin(k * t),
            "x_d": 0.05 * np.cos(t) + 0.01 * k, "y_d": 0.2 + 0.05 * np.sin(t) - 0.001 * k,
            "tau1": 0.3 * k * np.sin(3 * t), "tau2": -0.2 * k * t, "i1": 2.0 * k * np.cos(t), "i2": -k * t ** 2}


def _row(strategy, frequency, balanced):
    """A row whose every number tells its strategy, frequency and balance apart."""
    s = {"TCx": 1.0, "PDx": 2.0}.get(strategy, 3.0)
    b = 1.0 if balanced else 0.0
    return {"strategy": strategy, "frequency_Hz": frequency, "balanced": balanced,
            "e_ef_mm": 0.1 * s + frequency + 0.01 * b, "tau_ef_Nm": 0.2 * s * frequency + b,
            "tau1_peak_Nm": 0.5, "tau2_peak_Nm": 0.25, "i1_rms_A": s + frequency + 2 * b, "i2_rms_A": 2.5 * frequency + b,
            "i_peak_A": 7.0 + s, "v_peak_V": 12.0, "saturated_pct": 0.0, "i_peak_run_A": 9.0 + b,
            "error": "drive1: refused" if balanced and frequency > 1.5 else ""}


@pytest.fixture
def made_up(monkeypatch):
    """``measure`` replaced; each figure kept when closed.  Gives (calls, figures)."""
    import matplotlib.pyplot as plt

    calls, figures = [], []
    close = plt.close

    def measure(strategy, frequency, balanced):
        calls.append((strategy, frequency, balanced))
        return _row(strategy, frequency, balanced), _columns(balanced)

    def keep(fig=None):
        figures.append(fig)
        close(fig)

    monkeypatch.setattr(balancing, "measure", measure)
    monkeypatch.setattr(plt, "close", keep)
    return calls, figures


def _xy(line):
    return np.asarray(line.get_xdata(), dtype=float), np.asarray(line.get_ydata(), dtype=float)


def test_the_circle_figure_plots_each_run_in_mm_and_its_signals_against_time(made_up, tmp_path):
    """Catches the path or the reference in metres (3501's [18]), x and y swapped, the
    reference taken from the other run, a torque or current of the other drive or run, a run
    left out, and a panel's time axis, quantity or range not labelled as it is."""
    calls, figures = made_up
    balancing.plot_circle("TCx", tmp_path / "circle.png")
    assert calls == [("TCx", 1.0, False), ("TCx", 1.0, True)] and (tmp_path / "circle.png").stat().st_size > 0
    path, signals, currents = figures[0].axes
    plain, heavy = _columns(False), _columns(True)
    expected = [(1e3 * plain["x"], 1e3 * plain["y"], "plain"), (1e3 * heavy["x"], 1e3 * heavy["y"], "balanced"),
                (1e3 * heavy["x_d"], 1e3 * heavy["y_d"], "reference")]
    assert len(path.lines) == 3
    for line, (x, y, label) in zip(path.lines, expected):
        assert line.get_label() == label
        assert np.array_equal(_xy(line)[0], x) and np.array_equal(_xy(line)[1], y), label
    for axes, name in ((signals, "tau"), (currents, "i")):
        wanted = [(c["t"], c[f"{name}{j}"], f"{label} {name}{j}") for label, c in (("plain", plain), ("balanced", heavy))
                  for j in ("1", "2")]
        assert [line.get_label() for line in axes.lines] == [w[2] for w in wanted]
        for line, (t, v, label) in zip(axes.lines, wanted):
            assert np.array_equal(_xy(line)[0], t) and np.array_equal(_xy(line)[1], v), label
    assert path.get_xlabel() == "x [mm]" and path.get_ylabel() == "y [mm]"
    assert (signals.get_xlabel(), signals.get_ylabel(), signals.get_ylim()) == ("t [s]", "torque command [N m]", (-1, 1))
    assert (currents.get_xlabel(), currents.get_ylabel(), currents.get_ylim()) == ("t [s]", "drive current [A]",
                                                                                   (-15, 15))


def test_the_sweep_figure_draws_each_strategy_and_balance_from_its_own_rows(made_up, tmp_path):
    """Catches a curve of another strategy's or balance's rows, the RMS current of one drive
    instead of the worse, the axes' quantities swapped, and the driver's 12 A line moved."""
    _, figures = made_up
    rows = [_row(s, f, b) for s in ("TCx", "PDx") for f in (0.5, 1.0, 2.0) for b in (False, True)]
    balancing.plot_sweep(rows, tmp_path / "sweep.png")
    torque, current, error = figures[0].axes
    for k, (s, b) in enumerate((s, b) for s in ("TCx", "PDx") for b in (False, True)):
        mine = [r for r in rows if r["strategy"] == s and r["balanced"] == b]
        f = [r["frequency_Hz"] for r in mine]
        label = f"{s} {'balanced' if b else 'plain'}"
        for axes, values in ((torque, [r["tau_ef_Nm"] for r in mine]),
                             (current, [max(r["i1_rms_A"], r["i2_rms_A"]) for r in mine]),
                             (error, [r["e_ef_mm"] for r in mine])):
            line = axes.lines[k]
            assert line.get_label() == label and _xy(line)[0].tolist() == f and _xy(line)[1].tolist() == values
    limit = current.lines[4]
    assert limit.get_label() == "driver continuous 12 A" and set(_xy(limit)[1]) == {balancing.CONTINUOUS_A}


def test_the_scenes_table_has_a_row_per_scene_with_its_numbers(made_up):
    """Catches a row's numbers from another scene, the digits of a column, the two drives'
    figures swapped and the run's error left out."""
    calls, _ = made_up
    lines = balancing.scene_table(("TCx", "PDx")).splitlines()
    assert calls == [(s, 1.0, b) for s in ("TCx", "PDx") for b in (False, True)]
    assert lines[2] == "| TCx | no | 1.100 | 0.200 | 0.50, 0.25 | 2.00, 2.50 | 8.0 / 9.0 | 12.0 |"
    assert lines[3] == "| TCx | yes | 1.110 | 1.200 | 0.50, 0.25 | 4.00, 3.50 | 8.0 / 10.0 | 12.0 |"
    assert lines[5] == "| PDx | yes | 1.210 | 1.400 | 0.50, 0.25 | 5.00, 3.50 | 9.0 / 10.0 | 12.0 |" and len(lines) == 6


def test_the_command_line_writes_the_csv_and_figures_and_prints_the_crossings(made_up, tmp_path, capsys):
    """Catches a row missing from the csv or a value not read back to six digits, a figure not
    written where asked, and a crossing printed of another quantity; the output folder and its
    missing parent made (sibling of seed 4201 [196])."""
    calls, _ = made_up
    out = tmp_path / "new" / "out"
    assert balancing.main(["--strategies", "TCx", "--frequencies", "1", "2", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["balanced_circle.png", "balanced_speeds.csv", "balanced_speeds.png"]
    with open(out / "balanced_speeds.csv", newline="") as handle:
        back = list(csv.DictReader(handle))
    rows = [_row("TCx", f, b) for f in (1.0, 2.0) for b in (False, True)]
    assert len(back) == 4
    for read, row in zip(back, rows):
        assert read == {k: (f"{v:.6g}" if isinstance(v, float) else str(v)) for k, v in row.items()}
    printed = capsys.readouterr().out.splitlines()
    assert printed[-3:] == [f"TCx: balanced and plain {key} cross at no frequency in the sweep"
                            for key in ("tau_ef_Nm", "i1_rms_A", "e_ef_mm")]
