"""scenarios/studies/balancing.py's numbers without its long runs: a row of ``measure`` from the
columns of a run given here (run_scene replaced by one returning them), each entry against its
definition computed here, and ``break_even``'s crossing against the straight lines through the
points (issue 31: the scenarios' weakest area; values compared with an independent computation)."""
from __future__ import annotations

import csv
from types import SimpleNamespace

import numpy as np
import pytest

from motor import get_motor_preset
from scenarios.studies import balancing


def _outcome(error=""):
    """A vertical circle's run at 2 ms: window [1, 3] s in a 4 s run, a current peak outside the
    window, one drive saturated on part of it."""
    t = np.arange(2001) * 2e-3
    v_max = get_motor_preset("motor1").v_max
    columns = {"t": t, "tau1": 0.3 * np.sin(3 * t), "tau2": -0.5 * np.cos(2 * t) + 0.1,
               "i1": 2.0 * np.sin(3 * t) + 0.5, "i2": -1.5 * np.cos(2 * t),
               "v1": np.clip(30.0 * np.sin(5 * t), -v_max, v_max), "v2": 3.0 * np.cos(t)}
    columns["i2"][1800] = -25.0                                   # at 3.6 s: outside the window
    scene = SimpleNamespace(window=(1.0, 3.0))
    return SimpleNamespace(columns=columns, metrics={"e_ef_mm": 0.75, "tau_ef_Nm": 0.125}, scene=scene,
                           result=SimpleNamespace(error=error))


def test_a_row_is_each_quantitys_definition_over_the_window(monkeypatch):
    """Catches the window's ends, a peak of the signed value, the RMS of the wrong current,
    the saturation share of the run or with the wrong bound, the run's peak taken over the
    window, the error text lost."""
    outcome = _outcome(error="drive1: refused")
    asked = []
    monkeypatch.setattr(balancing, "run_scene", lambda scene: asked.append(scene) or outcome)
    row, columns = balancing.measure("TCMDx", 0.75, True)
    assert columns is outcome.columns and asked[0].name.startswith("vertical_circle")
    c = outcome.columns
    window = [k for k in range(len(c["t"])) if 500 <= k <= 1500]            # [1, 3] s at 2 ms
    v_max = get_motor_preset("motor1").v_max
    volts = [max(abs(c["v1"][k]), abs(c["v2"][k])) for k in window]
    expected = {
        "strategy": "TCMDx", "frequency_Hz": 0.75, "balanced": True, "e_ef_mm": 0.75, "tau_ef_Nm": 0.125,
        "tau1_peak_Nm": max(abs(c["tau1"][k]) for k in window), "tau2_peak_Nm": max(abs(c["tau2"][k]) for k in window),
        "i1_rms_A": (sum(c["i1"][k] ** 2 for k in window) / len(window)) ** 0.5,
        "i2_rms_A": (sum(c["i2"][k] ** 2 for k in window) / len(window)) ** 0.5,
        "i_peak_A": max(max(abs(c["i1"][k]), abs(c["i2"][k])) for k in window),
        "v_peak_V": max(volts),
        "saturated_pct": 100.0 * sum(v >= v_max for v in volts) / len(volts),
        "i_peak_run_A": 25.0, "error": "drive1: refused"}
    assert row.keys() == expected.keys() and tuple(row) == balancing.COLUMNS
    for key, value in expected.items():
        assert row[key] == (pytest.approx(value, rel=1e-12) if isinstance(value, float) else value), key
    assert 0.0 < row["saturated_pct"] < 100.0 and row["i_peak_A"] < 25.0


def test_break_even_is_where_the_straight_lines_between_the_points_cross():
    """Balanced minus plain torque changes sign between 1 and 1.5 Hz; the crossing of the line
    through the two gaps.  Another strategy's rows are ignored; no crossing gives None."""
    plain = {0.5: 0.10, 1.0: 0.20, 1.5: 0.45, 2.0: 0.80}
    heavy = {0.5: 0.15, 1.0: 0.23, 1.5: 0.30, 2.0: 0.40}
    rows = [{"strategy": "PDx", "frequency_Hz": f, "balanced": b, "tau_ef_Nm": (heavy if b else plain)[f]}
            for f in plain for b in (False, True)]
    rows += [{"strategy": "TCx", "frequency_Hz": f, "balanced": True, "tau_ef_Nm": -5.0} for f in plain]
    g0, g1 = heavy[1.0] - plain[1.0], heavy[1.5] - plain[1.5]
    assert balancing.break_even(rows, "PDx") == pytest.approx(1.0 + 0.5 * g0 / (g0 - g1), rel=1e-12)
    rising = [dict(r, tau_ef_Nm=r["tau_ef_Nm"] + (1.0 if r["balanced"] else 0.0))
              for r in rows if r["strategy"] == "PDx"]
    assert balancing.break_even(rising, "PDx") is None


def test_the_csv_has_the_columns_in_order_and_six_significant_digits(tmp_path):
    """Catches balancing.csv with its columns out of order or its numbers rounded to other than six
    significant digits."""
    path = tmp_path / "balancing.csv"
    row = {name: 0.0 for name in balancing.COLUMNS} | {"strategy": "TCx", "balanced": False, "error": "",
                                                       "e_ef_mm": 1.23456789, "frequency_Hz": 0.25}
    balancing.write_csv([row], path)
    with open(path, newline="") as handle:
        back = list(csv.DictReader(handle))
    assert list(back[0]) == list(balancing.COLUMNS)
    assert back[0]["e_ef_mm"] == "1.23457" and back[0]["frequency_Hz"] == "0.25" and back[0]["balanced"] == "False"


def test_break_even_at_a_point_where_balanced_and_plain_are_equal_is_that_point():
    """Gaps (balanced - plain) exactly zero at a sweep point: a zero is on the "at most plain" side,
    so the crossing is that point when the gap is positive on its other side (rising from the
    first point, falling into the last, through a middle one) and there is none where the gap
    only touches zero from below.  Catches a zero gap taken as either side's strict sign (the
    next pair's crossing, or None, instead)."""
    freqs = (0.5, 1.0, 1.5, 2.0)

    def rows(gaps):
        return [r for f, g in zip(freqs, gaps) for r in (
            {"strategy": "PDq", "frequency_Hz": f, "balanced": False, "tau_ef_Nm": 0.5},
            {"strategy": "PDq", "frequency_Hz": f, "balanced": True, "tau_ef_Nm": 0.5 + g})]

    for gaps, crossing in (((0.0, 0.25, 0.5, 0.75), 0.5), ((0.0, -0.25, -0.5, -0.75), None),
                           ((-0.25, 0.0, 0.25, 0.5), 1.0), ((0.25, 0.0, -0.25, -0.5), 1.0),
                           ((0.5, 0.25, 0.125, 0.0), 2.0), ((-0.5, -0.25, -0.125, 0.0), None),
                           ((-0.25, 0.0, -0.25, 0.25), 1.75), ((0.25, 0.125, -0.125, 0.0), 1.25)):
        assert balancing.break_even(rows(gaps), "PDq") == crossing, gaps
