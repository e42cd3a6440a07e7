"""scenarios/studies/balancing.py's window, sample for sample (issue 31, training seed 4431 [7]).

The module's docstring: the peaks, RMS currents, voltages and saturation share are taken "over
the metric window" -- the samples :func:`scenarios.run.metrics.scene_metrics` takes e_ef and
tau_ef over, ``start - 1e-9 <= t <= end + 1e-9`` (a nanosecond of slack for a sample time's
rounding).  A run is made up here (``run_scene`` replaced) with one marked sample at each of
these times: each mark shows up in the row exactly when its sample is in the window.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from motor import get_motor_preset
from scenarios.studies import balancing

START, END = 1.0, 3.0
#: The slack scene_metrics allows on either side of the window [s].
EPS = 1e-9


def _row(monkeypatch, probes: dict):
    """``measure``'s row for a run on a 4 ms grid from START to END (both exactly) and a sample
    before the window, plus the ``probes`` (time -> (column, value)); every other sample 0.01."""
    grid = set(np.arange(501) * 4e-3 + START)
    t = np.array(sorted(grid | {START - 0.5} | set(probes)))
    columns = {name: np.full(len(t), 0.01) for name in ("tau1", "tau2", "i1", "i2", "v1", "v2")}
    for time, (name, value) in probes.items():
        columns[name][int(np.flatnonzero(t == time)[0])] = value
    columns["t"] = t
    outcome = SimpleNamespace(columns=columns, metrics={"e_ef_mm": 0.5, "tau_ef_Nm": 0.25},
                              scene=SimpleNamespace(window=(START, END)), result=SimpleNamespace(error=""))
    monkeypatch.setattr(balancing, "run_scene", lambda scene: outcome)
    row, _ = balancing.measure("TCx", 1.0, False)
    return row


def test_samples_within_the_nanosecond_slack_are_in_the_window_and_farther_ones_are_not(monkeypatch):
    """Half the slack outside either end: in (its mark is the row's peak); one and a half times
    the slack outside: out (its larger mark is not).  Catches a wider or narrower slack, and
    a window end read from the other end or dropped."""
    row = _row(monkeypatch, {START - 0.5 * EPS: ("tau1", 2.0), START - 1.5 * EPS: ("tau1", 7.0),
                             END + 0.5 * EPS: ("tau2", 3.0), END + 1.5 * EPS: ("tau2", 9.0),
                             START + 0.002: ("i1", 4.0)})
    assert row["tau1_peak_Nm"] == 2.0 and row["tau2_peak_Nm"] == 3.0
    assert row["i_peak_A"] == 4.0 and row["i_peak_run_A"] == 4.0


def test_the_window_ends_themselves_are_in_the_window(monkeypatch):
    """Marks at START and at END exactly (grid samples) are the row's peaks; the sample half a
    second before the window is not."""
    row = _row(monkeypatch, {START: ("i2", -6.0), END: ("v2", 5.0), START - 0.5: ("tau1", 8.0)})
    assert row["i_peak_A"] == 6.0 and row["v_peak_V"] == 5.0 and row["tau1_peak_Nm"] == 0.01
    assert row["i2_rms_A"] == pytest.approx(((6.0 ** 2 + 500 * 0.01 ** 2) / 501) ** 0.5, rel=1e-12)


def test_the_saturation_share_counts_the_samples_at_the_supply_voltage(monkeypatch):
    """Samples at exactly the supply's v_max are saturated, and so is one at the bound's rounding
    slack exactly, v_max (1 - 1e-9); one a part in 10^6 below is not (the share's bound is v_max
    up to rounding); the window has 501 + 4 samples here.  Catches ``>`` for ``>=``."""
    v_max = get_motor_preset("motor1").v_max
    row = _row(monkeypatch, {START + 0.001: ("v1", v_max), START + 0.003: ("v2", -v_max),
                             START + 0.005: ("v1", v_max * (1 - 1e-6)), START + 0.007: ("v2", v_max * (1 - 1e-9))})
    n = 501 + 4
    assert row["saturated_pct"] == pytest.approx(100.0 * 3 / n, rel=1e-12)
    assert row["v_peak_V"] == v_max


def test_a_sample_exactly_the_slack_before_the_start_is_in_the_window_as_in_scene_metrics(monkeypatch):
    """The metric window is closed: ``t >= start - 1e-9`` (scenarios/run/metrics.py)."""
    row = _row(monkeypatch, {START - EPS: ("tau1", 2.0)})
    assert row["tau1_peak_Nm"] == 2.0


def test_a_sample_exactly_the_slack_after_the_end_is_in_the_window_as_in_scene_metrics(monkeypatch):
    """The metric window is closed: ``t <= end + 1e-9`` (scenarios/run/metrics.py)."""
    row = _row(monkeypatch, {END + EPS: ("tau2", 3.0)})
    assert row["tau2_peak_Nm"] == 3.0
