"""The twin report's verdict and figure (scenarios/studies/twin_fit.py ``_verdict``, ``plot``) on
runs made up here: each predicted triangle e_ef is a chosen multiple of the thesis bench's
(SYSTEM.md's table), so the counts and the bars are known without running a scene."""
from __future__ import annotations

import json

import numpy as np
import pytest

from scenarios.batch.report import THESIS_BENCH
from scenarios.studies import twin_fit

#: Predicted / bench triangle e_ef per strategy (circle: 1.1 for all).
RATIOS = {"PDq": 1.0, "PDMDq": 1.0, "TCq": 1.4, "TCMDq": 0.6, "PDx": 1.6, "PDMDx": 0.45, "TCx": 0.75, "TCMDx": 2.0}
SEEDS = (101, 102, 103)
#: Each seed's value is the mean times these (mean 1, min 0.9, max 1.2).
SPREAD = (0.9, 0.9, 1.2)


def _runs():
    runs = {}
    for kind in ("circle", "triangle"):
        runs[kind] = {}
        for s in twin_fit.ORDER:
            ratio = RATIOS[s] if kind == "triangle" else 1.1
            e_ef, tau_ef, e_ss = (THESIS_BENCH[kind][s][i] for i in (0, 1, 4))
            runs[kind][s] = {seed: {"e_ef_mm": ratio * e_ef * f, "tau_ef_Nm": 1.3 * tau_ef * f, "e_ss_mm": 2.0 * e_ss * f}
                             for seed, f in zip(SEEDS, SPREAD)}
    return runs


def test_the_verdict_counts_the_strategies_within_30_and_50_percent_and_the_pairs_md_improves():
    """Triangle ratios 1.0, 1.0, 1.4, 0.6, 1.6, 0.45, 0.75, 2.0 (PDq ... TCMDx): 3 of 8 within
    ±30 % (PDq, PDMDq, TCx), 5 within ±50 %; the MD term lowers e_ef in 3 of 4 pairs (not TCx ->
    TCMDx).  Catches ratios taken against another table entry, the counts against the
    circle, and the list handling of the report's lines."""
    lines = twin_fit._verdict(_runs())
    assert lines[0] == "## The prediction against the goals" and lines[-1] == ""
    ratios = ", ".join(f"{s} {RATIOS[s]:.2f}" for s in twin_fit.ORDER)
    assert lines[2] == ("- Predicted triangle e_ef within ±30 % of the bench: 3 of 8 (PDq, PDMDq, TCx); "
                        f"within ±50 %: 5 of 8; ratios {ratios}.")
    assert lines[3] == "- The sliding-mode term lowers the predicted triangle e_ef (seed mean) in 3 of 4 pairs."


def test_the_verdicts_bands_are_closed_a_half_is_within_50_percent_and_a_tie_is_no_improvement():
    """One seed, triangle e_ef exactly 0.5 (a power of two: the ratio is exactly 0.5) or 1.0 or
    2.0 times the bench: |0.5 - 1| = 0.50 is within ±50 % (the band is closed), 2.0 is not; a
    pair whose MD run ties its pure run does not lower e_ef.  (The ±30 % edge cannot be met by a
    double: r - 1 is exact for r in [0.5, 2] and a multiple of 2^-53, the double 0.30 is not, so
    its '<=' and '<' agree; seed 4001 [62].)"""
    factor = {"PDq": 0.5, "PDMDq": 0.5, "TCq": 1.0, "TCMDq": 1.0, "PDx": 2.0, "PDMDx": 0.5, "TCx": 1.0, "TCMDx": 0.5}
    runs = {kind: {s: {1: {"e_ef_mm": (factor[s] if kind == "triangle" else 1.0) * THESIS_BENCH[kind][s][0]}}
                   for s in twin_fit.ORDER} for kind in ("circle", "triangle")}
    assert all(runs["triangle"][s][1]["e_ef_mm"] / THESIS_BENCH["triangle"][s][0] == factor[s] for s in factor)
    runs["triangle"]["PDMDq"] = runs["triangle"]["PDq"]     # a tie: 0.5 x 5.39 / 5.16 = 0.52, within ±50 %
    lines = twin_fit._verdict(runs)
    assert lines[2].startswith("- Predicted triangle e_ef within ±30 % of the bench: 3 of 8 (TCq, TCMDq, TCx); "
                               "within ±50 %: 7 of 8; ratios PDq 0.50, PDMDq 0.52, TCq 1.00, TCMDq 1.00, PDx 2.00")
    # MD lowers e_ef: not PDq -> PDMDq (tie); TCq -> TCMDq (the bench's 1.63 < 1.85), PDx -> PDMDx
    # (0.5 x 1.79 < 2 x 1.98), TCx -> TCMDx (0.5 x 1.36 < 1.83)
    assert lines[3] == "- The sliding-mode term lowers the predicted triangle e_ef (seed mean) in 3 of 4 pairs."


def test_the_figure_shows_the_seed_mean_with_min_max_bars_beside_the_bench(tmp_path, monkeypatch):
    """Each panel: the twin's bars at x - 0.2, 0.4 wide, as high as the seeds' mean, with error bars
    from the seeds' minimum to their maximum; the bench's bars at x + 0.2 as high as SYSTEM.md's
    table (e_ef, τ_ef, e_ss), also 0.4 wide so the pair abuts.  Catches the bar's height and width
    swapped, the bench's width dropped (0.8 wide, hiding the twin's bar), the spread read from
    the wrong axis of the statistics, or another table column."""
    import matplotlib.pyplot as plt
    from matplotlib.container import BarContainer

    kept = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    runs = _runs()
    assert twin_fit.plot(runs, tmp_path / "twin.png") == tmp_path / "twin.png"
    assert (tmp_path / "twin.png").stat().st_size > 0
    axes = np.array(kept[0].axes).reshape(3, 2)
    x = np.arange(8)
    for col, kind in enumerate(("circle", "triangle")):
        for row, (key, index) in enumerate((("e_ef_mm", 0), ("tau_ef_Nm", 1), ("e_ss_mm", 4))):
            twin, bench = (c for c in axes[row, col].containers if isinstance(c, BarContainer))
            values = np.array([[runs[kind][s][seed][key] for seed in SEEDS] for s in twin_fit.ORDER])
            heights = [p.get_height() for p in twin.patches]
            assert heights == pytest.approx(values.mean(axis=1), rel=1e-12)
            assert [p.get_width() for p in twin.patches] == pytest.approx([0.4] * 8)
            assert [p.get_x() + p.get_width() / 2 for p in twin.patches] == pytest.approx(x - 0.2)
            segments = twin.errorbar.lines[2][0].get_segments()
            low, high = (np.array([seg[i][1] for seg in segments]) for i in (0, 1))
            assert low == pytest.approx(values.min(axis=1), rel=1e-12)
            assert high == pytest.approx(values.max(axis=1), rel=1e-12)
            assert [p.get_height() for p in bench.patches] == pytest.approx(
                [THESIS_BENCH[kind][s][index] for s in twin_fit.ORDER], rel=1e-12)
            assert [p.get_x() + p.get_width() / 2 for p in bench.patches] == pytest.approx(x + 0.2)
            # The pair abuts: the bench's bar starts where the twin's ends, neither hides the other.
            assert [p.get_x() for p in bench.patches] == pytest.approx([p.get_x() + p.get_width() for p in twin.patches])
            assert [p.get_width() for p in bench.patches] == pytest.approx([0.4] * 8)


def test_the_calibration_spread_lists_each_descent_end_by_loss_and_each_strategys_ratio_range():
    """Two descent ends (losses 0.3 and 0.1, listed by loss, each with its parameters) whose
    triangle runs are 1.0 and 1.5 times the bench and circle runs 0.8 and 1.2 times: every
    strategy's ranges read 0.80–1.20 and 1.00–1.50.  Catches the ends unsorted, the range's ends
    swapped, the ratio against the other trajectory and the section's closing blank line lost."""
    def runs(circle, triangle):
        return {kind: {s: {"e_ef_mm": f * THESIS_BENCH[kind][s][0]} for s in twin_fit.ORDER}
                for kind, f in (("circle", circle), ("triangle", triangle))}

    other = twin_fit.Twin(**{**twin_fit.START.values(), "friction_scale": 2 * twin_fit.START.friction_scale})
    lines = twin_fit._render_spread([(0.3, other, runs(1.2, 1.5)), (0.1, twin_fit.START, runs(0.8, 1.0))])
    assert lines[0].startswith("## Calibration spread: the ends of the fit's 2 descents") and lines[-1] == ""
    first, second = (next(line for line in lines if line.startswith(f"| {i} |")) for i in (0, 1))
    assert first == "| 0 | 0.1000 | " + " | ".join(f"{v:.3g}" for v in twin_fit.START.values().values()) + " |"
    assert second == "| 1 | 0.3000 | " + " | ".join(f"{v:.3g}" for v in other.values().values()) + " |"
    for s in twin_fit.ORDER:
        assert f"| {s} | 0.80–1.20 | 1.00–1.50 |" in lines


def test_the_report_tables_give_each_strategys_mean_spread_ratio_and_each_pairs_change():
    """twin.md's rows from made-up runs: e_ef, τ_ef, e_ss as seed mean [min–max] beside the bench,
    ratios ours / bench, settled seeds counted; the MD pair's change (mean MD / mean pure - 1) beside
    Tables 11-12's, 'yes' only when MD is lower for every seed.  Catches a column from the wrong
    statistic or table entry, a ratio inverted, the change's sign, the every-seed rule as any-seed."""
    runs = _runs()
    for kind in runs:
        for s in twin_fit.ORDER:
            for k, m in enumerate(runs[kind][s].values()):
                m.update(settled=k != 0 or s != "TCx", e_contour_sides_mm=[0.1, 0.2, 0.3])
    # PDx -> PDMDx: MD lower on average and on every seed; TCq -> TCMDq on the circle: not on seed 103
    runs["circle"]["TCMDq"][103]["e_ef_mm"] = 10.0
    text = twin_fit.render(runs, twin_fit.START, {"loss": 0.25, "start_loss": 1.5, "evaluations": 7, "seeds": [1]})
    lines = text.splitlines()
    circle = lines.index("## Circle: fitted (Tables 9, 13)")
    triangle = lines.index("## Triangle: predicted without refitting (Tables 10, 14)")
    for kind, start in (("circle", circle), ("triangle", triangle)):
        section = lines[start:]
        for s in twin_fit.ORDER:
            v = np.array([[runs[kind][s][seed][k] for seed in SEEDS] for k in ("e_ef_mm", "tau_ef_Nm", "e_ss_mm")])
            mean, low, high = v.mean(axis=1), v.min(axis=1), v.max(axis=1)
            be, bt, bss = (THESIS_BENCH[kind][s][i] for i in (0, 1, 4))
            settled = 2 if s == "TCx" else 3
            row = (f"| {s} | {mean[0]:.3f} [{low[0]:.3f}–{high[0]:.3f}] | {be:.2f} | {mean[0] / be:.2f} | "
                   f"{mean[1]:.3f} [{low[1]:.3f}–{high[1]:.3f}] | {bt:.3f} | {mean[1] / bt:.2f} | "
                   f"{mean[2]:.3f} [{low[2]:.3f}–{high[2]:.3f}] | {bss:.3f} | {settled}/3 |")
            assert row in section, row
        for pure, md in (("PDx", "PDMDx"), ("TCq", "TCMDq")):
            e = {x: np.mean([runs[kind][x][seed]["e_ef_mm"] for seed in SEEDS]) for x in (pure, md)}
            every = all(runs[kind][md][seed]["e_ef_mm"] < runs[kind][pure][seed]["e_ef_mm"] for seed in SEEDS)
            row = (f"| {pure} → {md} | {100 * (e[md] / e[pure] - 1):+.1f} % | "
                   f"{twin_fit.THESIS_MD_CHANGE[kind][pure][0]:+.1f} % | {'yes' if every else 'no'} |")
            assert row in section, row
    assert any(line.startswith("| TCq → TCMDq |") and line.endswith("| no |") for line in lines[circle:triangle])
    assert "Fit: loss 0.2500 (start 1.5000), 7 evaluations of 8 circle runs × seeds [1]" in text


def test_the_report_command_writes_the_runs_the_tables_and_the_figure(tmp_path, monkeypatch):
    """``twin_fit report --out DIR`` on made-up runs (the scenes' runs replaced): twin_runs.json
    reads back as every run's kept metrics keyed by seed (other keys dropped), twin.md is the
    rendered tables, the figure's link and the method's link, twin.png is written; the fit is not
    run.  Catches the runs' file written elsewhere or not at all, a kept metric dropped, another
    key kept, the report or the figure missing from ``--out``, and ``--out`` made without its
    missing parent (sibling of seed 4201 [196])."""
    tmp_path = tmp_path / "new" / "out"
    runs = _runs()
    for kind in runs:
        for s in twin_fit.ORDER:
            for m in runs[kind][s].values():
                m.update(settled=True, completed=True, e_contour_sides_mm=[0.1, 0.2, 0.3], internal_state=[1, 2])
    asked = []
    monkeypatch.setattr(twin_fit, "predict", lambda twin, seeds: asked.append(seeds) or runs)
    monkeypatch.setattr(twin_fit, "sensitivity", lambda twin: {})
    monkeypatch.setattr(twin_fit, "calibration_spread", lambda fit_info: [])
    monkeypatch.setattr(twin_fit, "fit", lambda *a, **k: pytest.fail("'report' must not fit"))
    assert twin_fit.main(["report", "--out", str(tmp_path)]) == 0
    assert asked == [twin_fit.SPREAD_SEEDS]
    stored = json.loads((tmp_path / "twin_runs.json").read_text())
    assert stored == {kind: {s: {str(seed): {k: v for k, v in m.items() if k != "internal_state"}
                                 for seed, m in runs[kind][s].items()} for s in twin_fit.ORDER} for kind in runs}
    text = (tmp_path / "twin.md").read_text()
    assert text == (twin_fit.render(runs, twin_fit.load_twin(), twin_fit.read_fit(), {}, [])
                    + "![twin beside the bench](twin.png)\n\n" + twin_fit.METHOD_LINK)
    assert (tmp_path / "twin.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
