"""scenarios/examples/plot_derivators.py's printed figures against the text that quotes them,
docs/derivators.md (its tables parsed here, the script's lines built from them), and its
command line's options taking effect (issue 31: results against the cited text; options
actually used).  The figures' functions are checked against independent formulations in
tests/controller/test_derivator_figures.py; this holds the report, the neighbouring cut-offs
and the transient counts, which only the document states."""
from __future__ import annotations

import re
import sys

import pytest

from controller.derivators import DEFAULT_FC_ACC, DEFAULT_FC_VEL, Derivator
from scenarios.examples import plot_derivators as figures
from tests.support.paths import ROOT

DOC = (ROOT / "docs" / "derivators.md").read_text()
NUMBER = r"([0-9.]+)"


def _rows(pattern: str) -> list:
    found = re.findall(pattern, DOC, flags=re.M)
    assert found, f"docs/derivators.md has no row like {pattern!r}"
    return found


def _expected_report() -> list:
    """The lines report() prints for the default cut-offs, as docs/derivators.md quotes them."""
    (velocity_delay, acceleration_delay), = _rows(rf"^\| steady-state delay \| {NUMBER} ms \| {NUMBER} ms \|$")
    lines = [f"  delays: velocity {velocity_delay} ms, acceleration {acceleration_delay} ms"]
    for f, lag_v, gain_v, lag_a, gain_a in _rows(
            rf"^\| phase lag at {NUMBER} Hz[^|]*\| {NUMBER}° \(gain {NUMBER}\) \| {NUMBER}° \(gain {NUMBER}\) \|$"):
        lines.append(f"  {float(f):4g} Hz: velocity lag {lag_v:>5} deg, gain {gain_v}; "
                     f"acceleration lag {lag_a:>5} deg, gain {gain_a}")
    (white_v, white_a), = _rows(rf"^\| quantisation noise, white model \| {NUMBER} rad/s rms \| {NUMBER} rad/s² rms \|$")
    lines.append(f"  white quantisation noise (variance step^2/12): velocity {white_v} rad/s rms, "
                 f"acceleration {white_a} rad/s^2 rms")
    (sine_v, sine_a), = _rows(rf"^\| quantisation noise, counts of a 1 Hz, 0.5 rad sine \| {NUMBER} rad/s rms \| "
                              rf"{NUMBER} rad/s² rms \|$")
    bare, = _rows(rf"^\| same signal, bare backward difference \| {NUMBER} rad/s rms \|")
    lines.append(f"  encoder counts on a 1 Hz 0.5 rad sine: velocity {sine_v} rad/s rms (bare difference {bare}), "
                 f"acceleration {sine_a} rad/s^2 rms")
    for lam, margin, crossover, delayed, ideal in _rows(
            rf"^\| {NUMBER} \| {NUMBER}° \| {NUMBER} Hz \| {NUMBER}° \| {NUMBER}° \|$"):
        lines.append(f"  lambda {lam} rad/s: phase margin {margin} deg at {crossover} Hz ({delayed} deg with one "
                     f"more step of delay; ideal {ideal} deg)")
    ramp_v, = _rows(rf"^\| velocity of a ramp \| {NUMBER} \|$")
    parabola_a, = _rows(rf"^\| acceleration of a parabola \| {NUMBER} \|$")
    ramp_a, = _rows(rf"^\| acceleration of a ramp[^|]*\| {NUMBER} \|$")
    lines.append(f"  within 1e-09 relative from sample: ramp velocity {ramp_v}, ramp acceleration {ramp_a}, "
                 f"parabola acceleration {parabola_a}")
    return lines


def test_the_report_prints_the_figures_docs_derivators_md_quotes(capsys):
    """Catches a delay, lag, gain, noise figure, phase margin, crossover or transient count of
    the report computed otherwise than the document's (another frequency, loop, delay, count,
    sample from which the transient is over) or printed in the wrong place."""
    figures.report(Derivator(DEFAULT_FC_VEL, DEFAULT_FC_ACC))
    printed = capsys.readouterr().out.splitlines()
    assert printed[0] == f"fc_vel = {DEFAULT_FC_VEL:g} Hz, fc_acc = {DEFAULT_FC_ACC:g} Hz, T = 0.001 s"
    assert printed[1:] == _expected_report()


def test_the_neighbouring_cut_offs_are_the_documents_tables(capsys):
    """Catches a neighbouring cut-off's delay, lags, noise or margins computed for another
    cut-off, frequency, loop or delay than the document's tables state."""
    figures.compare_cutoffs()
    printed = capsys.readouterr().out.splitlines()
    velocity = [f"  {float(fc):5g} Hz: {delay} ms, {lag5}/{lag11} deg, {noise} rad/s, {plain}/{late} deg"
                for fc, delay, lag5, lag11, noise, plain, late in _rows(
                    rf"^\| \**{NUMBER} Hz\** \| {NUMBER} ms \| {NUMBER}° / {NUMBER}° \| {NUMBER} rad/s \| "
                    rf"{NUMBER}° / {NUMBER}° \|$")]
    acceleration = [f"  {float(fc):5g} Hz: {delay} ms, {lag1}/{lag5}/{lag11} deg, {noise} rad/s^2"
                    for fc, delay, lag1, lag5, lag11, noise in _rows(
                        rf"^\| \**{NUMBER} Hz\** \| {NUMBER} ms \| {NUMBER}° / {NUMBER}° / {NUMBER}° \| "
                        rf"{NUMBER} rad/s² \|$")]
    assert len(velocity) == 4 and len(acceleration) == 4
    assert printed == ["velocity cut-off: delay, lag at 5/11 Hz, noise, phase margin at lambda 70 (plain / one "
                       "more step)", *velocity,
                       f"acceleration cut-off (fc_vel {DEFAULT_FC_VEL:g} Hz): delay, lag at 1/5/11 Hz, noise",
                       *acceleration]


@pytest.fixture
def main_calls(monkeypatch):
    """main() with its three outputs recorded instead of computed."""
    calls = []
    monkeypatch.setattr(figures, "report", lambda d: calls.append(("report", d.fc_vel, d.fc_acc, d.T)))
    monkeypatch.setattr(figures, "compare_cutoffs", lambda: calls.append(("compare",)))
    monkeypatch.setattr(figures, "plot_bode", lambda d, path: calls.append(("plot", d.fc_vel, d.fc_acc, path)))
    return calls


def test_docs_writes_the_documents_figure_and_out_another_path(main_calls, monkeypatch, tmp_path):
    """Catches ``--docs`` writing anywhere but the repository's docs/derivators_bode.png (the
    figure docs/derivators.md shows), ``--out`` ignored, and the default path not the one
    its help names."""
    monkeypatch.setattr(sys, "argv", ["plot_derivators", "--docs"])
    figures.main()
    assert main_calls[-1][3] == ROOT / "docs" / "derivators_bode.png"
    assert "derivators_bode.png" in DOC
    monkeypatch.setattr(sys, "argv", ["plot_derivators", "--out", str(tmp_path / "b.png")])
    figures.main()
    assert main_calls[-1][3] == str(tmp_path / "b.png")
    monkeypatch.setattr(sys, "argv", ["plot_derivators"])
    figures.main()
    assert main_calls[-1][3] == "out/derivators_bode.png"


def test_the_cut_off_options_reach_the_reported_and_plotted_derivator(main_calls, monkeypatch):
    """Catches ``--fc-vel``/``--fc-acc`` swapped, ignored, or given to one output only."""
    monkeypatch.setattr(sys, "argv", ["plot_derivators", "--fc-vel", "80", "--fc-acc", "50"])
    figures.main()
    assert main_calls == [("report", 80.0, 50.0, figures.SAMPLE_TIME), ("compare",),
                          ("plot", 80.0, 50.0, "out/derivators_bode.png")]
