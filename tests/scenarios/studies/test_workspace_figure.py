"""The workspace figure (scenarios/studies/workspace: ``user_circle``, ``draw`` through
``plot_workspace``): what is drawn where, read back from the figure."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from controller.model import DEFAULT_EXTENT
from scenarios.studies.workspace import figure, plot


@pytest.mark.parametrize("period", [1.0, 2.5])
def test_a_user_circle_turns_once_per_period_around_its_centre(period):
    """Every point at the radius from the centre; a quarter period a quarter turn from the start
    (cx, cy - r), half a period opposite it, a whole period back.  Catches the angle not 2π t /
    period (one radian per period, or per second)."""
    cx, cy, r = 0.01, 0.2, 0.03
    circle = figure.user_circle(cx, cy, r, period)
    assert circle(0.0) == pytest.approx((cx, cy - r), abs=1e-15)
    assert circle(period / 4) == pytest.approx((cx + r, cy), abs=1e-15)
    assert circle(period / 2) == pytest.approx((cx, cy + r), abs=1e-15)
    assert circle(period) == pytest.approx((cx, cy - r), abs=1e-15)
    for t in np.linspace(0.0, period, 17):
        x, y = circle(t)
        assert math.hypot(x - cx, y - cy) == pytest.approx(r, rel=1e-12)


def test_the_figure_draws_the_controllers_table_and_each_checked_circle_where_they_are(tmp_path, monkeypatch):
    """plot_workspace("bench") with a user circle: the dotted rectangle spans the controller's
    table (DEFAULT_EXTENT, also written to workspace.json), the user circle is drawn through its
    1 ms samples (radius r around its centre, a quarter turn at 250 ms).  Catches the rectangle's
    width or height from the wrong corners and a circle drawn at another rate."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    kept = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    cx, cy, r = 0.0, 0.2, 0.03
    report = plot.plot_workspace("bench", tmp_path, step=0.01, circles=[(cx, cy, r)])
    ax = kept[0].axes[0]
    x0, x1, y0, y1 = DEFAULT_EXTENT
    rectangles = [p for p in ax.patches if isinstance(p, Rectangle) and not p.get_fill()]
    assert len(rectangles) == 1
    box = rectangles[0]
    assert (box.get_x(), box.get_y(), box.get_width(), box.get_height()) == pytest.approx((x0, y0, x1 - x0, y1 - y0))
    assert json.loads((tmp_path / "workspace.json").read_text())["table_extent"] == list(DEFAULT_EXTENT)
    check = next(c for c in report.trajectories if c.name.startswith("circle (0, 0.2)"))
    line = next(li for li in ax.lines if len(li.get_xdata()) == len(check.x)
                and np.array_equal(li.get_xdata(), check.x) and np.array_equal(li.get_ydata(), check.y))
    xs, ys = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
    assert len(xs) == 1001 and np.allclose(np.hypot(xs - cx, ys - cy), r, rtol=1e-12)
    assert (xs[250], ys[250]) == pytest.approx((cx + r, cy), abs=1e-12)


def test_each_legend_entry_looks_like_what_it_labels(tmp_path, monkeypatch):
    """plot_workspace("bench") with a small circle and one far beyond the controller's table:
    each trajectory's line has the colour, width and style of its legend entry (one entry per
    trajectory, in their order), the table's rectangle those of its entry, and each kind of
    refusal that occurs is marked on the trajectory's refused samples with its entry's marker
    in red.  Catches a line drawn other than its legend says (colour, width, style), a
    trajectory or refusal missing from the legend, a refusal marked with another kind's
    marker or at other samples."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import to_rgba
    from matplotlib.patches import Rectangle

    kept = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    report = plot.plot_workspace("bench", tmp_path, step=0.01, circles=[(0.0, 0.2, 0.03), (0.0, 0.05, 0.2)])
    ax = kept[0].axes[0]
    legend = ax.get_legend()
    entries = {t.get_text(): h for h, t in zip(legend.legend_handles, legend.get_texts())}
    names = [c.name for c in report.trajectories]
    assert [label for label in entries if label in names] == names
    for check in report.trajectories:
        line = next(li for li in ax.lines if np.array_equal(li.get_xdata(), check.x)
                    and np.array_equal(li.get_ydata(), check.y) and li.get_linestyle() != "None")
        entry = entries[check.name]
        assert to_rgba(line.get_color()) == to_rgba(entry.get_color()), check.name
        assert (line.get_linewidth(), line.get_linestyle()) == (entry.get_linewidth(), entry.get_linestyle())
    box = next(p for p in ax.patches if isinstance(p, Rectangle) and not p.get_fill())
    table = entries["controller table (outside the band)"]
    assert to_rgba(box.get_edgecolor()) == to_rgba(table.get_color())
    assert (box.get_linewidth(), box.get_linestyle()) == (table.get_linewidth(), table.get_linestyle())
    refused = [(check, reason, idx) for check in report.trajectories for reason, idx in check.refused.items()
               if len(idx)]
    assert refused and {f"refused: {reason}" for _, reason, _ in refused} == {
        label for label in entries if label.startswith("refused: ")}
    for check, reason, idx in refused:
        entry = entries[f"refused: {reason}"]
        marks = next(li for li in ax.lines if li.get_linestyle() == "None"
                     and np.array_equal(li.get_xdata(), check.x[idx]) and np.array_equal(li.get_ydata(), check.y[idx]))
        assert marks.get_marker() == entry.get_marker() and to_rgba(marks.get_color()) == to_rgba("#e74c3c")
        assert to_rgba(entry.get_color()) == to_rgba("#e74c3c")


def test_the_printed_summary_names_each_trajectorys_margin_and_refusals_from_their_first_time():
    """``parcosim workspace``'s lines, from made-up checks at a 2 ms sample time: the figure's
    path, then per trajectory its smallest margin beside the band and "accepted", or the time
    of its first refused sample (the earliest over the reasons, index times the sample time)
    and each reason's count.  Catches the first refusal of one reason only, the count of
    another reason, the time in samples, and an accepted trajectory called refused."""
    from scenarios.studies.workspace.figure import BAND, OUTSIDE, TrajectoryCheck, WorkspaceReport

    xy = np.zeros(3)
    refused = TrajectoryCheck("circle (7.23)", xy, xy, {OUTSIDE: np.array([40, 41, 42]), BAND: np.array([17]),
                                                        "unused": np.array([], dtype=int)}, 0.0125, 2e-3)
    fine = TrajectoryCheck("triangle (7.24-7.27)", xy, xy, {OUTSIDE: np.array([], dtype=int)}, 0.25, 2e-3)
    report = WorkspaceReport("bench", "out/w/workspace.png", 0.02, [refused, fine])
    assert report.summary().splitlines() == [
        "bench: out/w/workspace.png",
        f"  circle (7.23): min singularity margin 0.013 (band 0.02); REFUSED from t = 0.034 s: "
        f"3 samples {OUTSIDE}, 1 samples {BAND}",
        "  triangle (7.24-7.27): min singularity margin 0.250 (band 0.02); accepted"]


def test_each_sample_is_refused_for_the_first_reason_that_holds_the_tables_edges_included():
    """Samples on each edge of a table (closed), just past each edge, one out of reach and one in
    the near-singular band: each refused for exactly the first of the controller's reasons that
    holds, computed here from fivebar.singularity, and the smallest margin over the reachable
    samples.  Catches an edge of the table taken as outside (a strict comparison), a reason
    tested out of order, a sample in two lists, the margin of an unreachable point counted."""
    from plant import get_preset
    from plant import fivebar

    params = get_preset("thesis_sim")
    extent = (-0.03, 0.05, 0.12, 0.2)
    pts = [(0.01, 0.16), (extent[0], 0.16), (extent[1], 0.16), (0.01, extent[2]), (0.01, extent[3]),
           (extent[0] - 1e-4, 0.16), (extent[1] + 1e-4, 0.16), (0.01, extent[2] - 1e-4), (0.01, extent[3] + 1e-4),
           (1.0, 1.0), (0.0, 0.08), (0.02, 0.15)]   # out of reach; in the band and off the table
    check = figure.check_trajectory(params, "edges", lambda t: pts[round(t / 1e-3)], (len(pts) - 1) * 1e-3,
                                    band=0.2, extent=extent)
    wanted = {figure.OUTSIDE: [], figure.BAND: [], figure.TABLE: []}
    margins = []
    for i, (x, y) in enumerate(pts):
        try:
            margin = fivebar.singularity(params, x, y).margin
        except fivebar.KinematicsError:
            wanted[figure.OUTSIDE].append(i)
            continue
        margins.append(margin)
        if margin < 0.2:
            wanted[figure.BAND].append(i)
        elif not (extent[0] <= x <= extent[1] and extent[2] <= y <= extent[3]):
            wanted[figure.TABLE].append(i)
    assert wanted[figure.TABLE] == [5, 6, 7, 8] and wanted[figure.OUTSIDE] == [9] and wanted[figure.BAND] == [10]
    assert {r: i.tolist() for r, i in check.refused.items()} == wanted
    assert check.min_margin == min(margins)


def test_a_trajectory_wholly_outside_the_workspace_is_written_as_strict_json_with_no_margin(tmp_path):
    """A circle far beyond the 5R's reach has no sample with a singularity margin: workspace.json
    says null (strict JSON: no Infinity or NaN, which other parsers refuse) and the printed summary
    says none, while a circle inside keeps its finite margin.  Catches the margin's default (inf)
    written as it is."""
    report = plot.plot_workspace("bench", tmp_path, step=0.01, circles=[(1.0, 1.0, 0.01), (0.0, 0.2, 0.03)])

    def refuse(constant):
        raise ValueError(f"not JSON: {constant}")

    written = json.loads((tmp_path / "workspace.json").read_text(), parse_constant=refuse)
    margins = {t["name"]: t["min_margin"] for t in written["trajectories"]}
    assert margins["circle (1, 1) r 0.01"] is None
    assert margins["circle (0, 0.2) r 0.03"] > 0.0
    assert "circle (1, 1) r 0.01: min singularity margin none (no sample inside)" in report.summary()


def test_the_output_folder_is_made_with_its_missing_parents(tmp_path, monkeypatch):
    """plot_workspace into a/b, neither existing, for a spec (its slice replaced here: only the
    folder is looked at) finds the folder made.  Catches the folder made without its parents
    (a FileNotFoundError; sibling of seed 4201 [196])."""
    seen = []
    monkeypatch.setattr(plot, "plot_spec_slice", lambda mechanism, out, band: seen.append(out.is_dir()) or out)
    assert plot.plot_workspace("bench_5r", tmp_path / "a" / "b") == tmp_path / "a" / "b" and seen == [True]
