"""scenarios/batch/report.py's steady-state and per-side tables from metrics given here (its other
tables: test_report.py): each cell is the metric it names, signed, to its digits; the sides of
larger error against the thesis' (issue 31: written values read back)."""
from __future__ import annotations

import math

from scenarios.batch.report import THESIS_BENCH, bench_scene_names, render, side_section, sides_hold


def _metrics():
    metrics = {}
    for k, name in enumerate(bench_scene_names()):
        kind, strategy = name.split("_")[1:]
        metrics[name] = {"completed": True, "e_ef_mm": 1.0 + k / 10, "tau_ef_Nm": 0.1, "e_ss_mm": 0.02 + k / 1000,
                         "e_ss_x_mm": -0.0125 * (k + 1), "e_ss_y_mm": 0.0031, "settled": k % 2 == 0,
                         "t_settle_s": 0.25 + k / 100, "e_ss_1s_mm": 0.5 + k / 100, "window_s": [1.0, 8.0],
                         "simulated_s": 11.0, "wall_s": 2.0, "realtime_factor": 5.5,
                         "e_contour_sides_mm": [0.3 + k / 100, 0.1, 0.2]}
    return metrics


def test_the_steady_state_rows_are_the_metrics_signed_and_settled_or_not():
    """Catches e_x and e_y swapped or unsigned, the settling time shown for a run that did not
    settle, e_ss_1s from another metric, the thesis' column from another table."""
    metrics = _metrics()
    lines = render(metrics, "inprocess").splitlines()
    names = bench_scene_names()
    for k, name in enumerate(names):
        kind, s = name.split("_")[1:]
        m = metrics[name]
        settle = f"{m['t_settle_s']:.2f}" if m["settled"] else "not settled"
        row = (f"| {s} | {m['e_ss_x_mm']:+.3f} | +0.003 | {m['e_ss_mm']:.3f} | {settle} | {m['e_ss_1s_mm']:.3f} | "
               f"{THESIS_BENCH[kind][s][-1]:.3f} |")
        assert row in lines, row
    assert "| PDq | -0.013 | +0.003 | 0.020 | 0.25 | 0.500 |" in "\n".join(lines)
    assert "| bench_circle_PDq | True | 11.000 | 2.00 | 5.5 |" in lines


def test_the_sides_of_larger_error_are_compared_with_the_thesis():
    """Side I largest: the claim (1,) holds; (1, 3) holds while side III is above side II and
    not when it is below; (2,) does not; a missing side or a tie is no claim held.  Catches the
    comparison of the named sides turned round, the side names off by one."""
    assert sides_hold([0.5, 0.1, 0.2], (1,)) and sides_hold([0.5, 0.1, 0.2], (1, 3))
    assert not sides_hold([0.5, 0.3, 0.2], (1, 3)) and not sides_hold([0.5, 0.1, 0.2], (2,))
    assert not sides_hold([0.5, math.nan, 0.2], (1,)) and not sides_hold([0.2, 0.2, 0.1], (1,))
    contour = {s: [0.5, 0.1, 0.2] for s in ("PDq", "PDMDq", "TCq", "TCMDq", "PDx", "PDMDx", "TCx", "TCMDx")}
    contour["PDMDq"] = [0.5, 0.3, 0.2]
    contour["PDx"] = [0.1, None, 0.2]                                 # side II not reached (JSON null)
    lines = side_section(contour)
    assert "| TCq | 0.50 | 0.10 | 0.20 | I | I | yes |" in lines
    assert "| PDq | 0.50 | 0.10 | 0.20 | I | I and III | yes |" in lines
    assert "| PDMDq | 0.50 | 0.30 | 0.20 | I | I and III | no |" in lines
    assert "| PDx | 0.10 | — | 0.20 | III | II | no |" in lines
    assert "The bench's sides of larger error hold here for 5 of 8 strategies." in lines


def test_metrics_without_the_per_side_errors_give_three_empty_sides_and_no_claim_held():
    """A metrics file from before ``e_contour_sides_mm`` (or a run that stopped before the
    triangle): each strategy's row has the triangle's three sides empty, no side of larger
    error, no claim held.  Catches another number of sides filled in, and a missing side
    counted as agreeing."""
    metrics = _metrics()
    for name in metrics:
        del metrics[name]["e_contour_sides_mm"]
    lines = render(metrics, "inprocess").splitlines()
    for s, claimed in (("PDq", "I and III"), ("TCx", "I"), ("PDMDx", "II")):
        assert f"| {s} | — | — | — | — | {claimed} | no |" in lines
    assert "The bench's sides of larger error hold here for 0 of 8 strategies." in lines


def test_every_heading_and_table_of_the_report_stands_apart_by_blank_lines():
    """Markdown blocks: each heading has a blank line before (but the first) and after it, each table
    a blank line before its header row and after its last row (or ends the text); the text ends in
    one newline.  A table row run into a heading or a paragraph is drawn as one more row by some
    renderers.  Catches a section's separating blank line dropped (seed 3901 [137]: the triangle's
    per-side section run into the steady-state table)."""
    stopped = _metrics()
    stopped["bench_circle_TCq"].update(completed=False, error="ctrl refused the step from t = 1 s: test")
    for metrics in (_metrics(), stopped):                # the second with its "Runs stopped early" paragraph
        text = render(metrics, "inprocess")
        assert text.endswith("\n") and not text.endswith("\n\n")
        lines = text.splitlines()
        for i, line in enumerate(lines):
            if line.startswith(("#", "**")):
                assert (i == 0 or lines[i - 1] == "") and lines[i + 1] == "", (i, line)
            if line.startswith("|") and not lines[i - 1].startswith("|"):
                assert lines[i - 1] == "" and lines[i + 1].startswith("|---"), (i, line)
            if line.startswith("|") and i + 1 < len(lines) and not lines[i + 1].startswith("|"):
                assert lines[i + 1] == "", (i, line)
        assert sum(line.startswith("### Where the triangle's error lies") for line in lines) == 1
    assert sum(line.startswith("**Runs stopped early:**") for line in lines) == 1
