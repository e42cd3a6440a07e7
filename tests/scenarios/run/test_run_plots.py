"""scenarios/run/runner.py ``plot_run`` for a five-bar scene on made-up columns (nothing runs):
each figure's lines read back exactly (the path in mm beside the reference, e = x_d - x in mm,
the torques in N m, against time), the labels, the metric window's edges and the files'
names (issue 31: every plotted value read back; seed 4001 [123], the time label's axis)."""
from __future__ import annotations

import matplotlib
import numpy as np
import pytest

from scenarios.run.runner import plot_run
from scenarios.scenes import get_scene

matplotlib.use("Agg")

SCENE = get_scene("bench_circle_TCMDx")


def _columns():
    t = np.arange(201) * 1e-3
    return {"t": t, "x": 0.02 * np.cos(t), "y": 0.1 + 0.02 * np.sin(t), "x_d": 0.021 * np.cos(t) + 1e-4,
            "y_d": 0.1 + 0.019 * np.sin(t), "tau1": 0.3 * np.sin(5 * t), "tau2": -0.2 * t}


@pytest.fixture
def figures(monkeypatch):
    """Each figure kept when closed."""
    import matplotlib.pyplot as plt

    kept, close = [], plt.close

    def keep(fig=None):
        kept.append(fig)
        close(fig)

    monkeypatch.setattr(plt, "close", keep)
    return kept


def _xy(line):
    return np.asarray(line.get_xdata(), dtype=float), np.asarray(line.get_ydata(), dtype=float)


def test_the_path_figure_is_the_end_effector_beside_the_reference_in_mm(figures, tmp_path):
    """Catches the path in metres, x and y swapped, the reference and the end effector swapped or
    a file missing."""
    c = _columns()
    files = plot_run(SCENE, c, tmp_path)
    assert [f.name for f in files] == ["path.png", "errors.png", "torques.png"]
    assert all(f.parent == tmp_path and f.stat().st_size > 0 for f in files)
    (ax,) = figures[0].axes
    assert [line.get_label() for line in ax.lines] == ["reference", "end effector"]
    for line, (x, y) in zip(ax.lines, ((c["x_d"], c["y_d"]), (c["x"], c["y"]))):
        assert np.array_equal(_xy(line)[0], 1e3 * x) and np.array_equal(_xy(line)[1], 1e3 * y)
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) == ("x [mm]", "y [mm]", SCENE.name)


@pytest.mark.parametrize("index, values, labels", [
    (1, lambda c: (1e3 * (c["x_d"] - c["x"]), 1e3 * (c["y_d"] - c["y"])), ("e_x [mm]", "e_y [mm]")),
    (2, lambda c: (c["tau1"], c["tau2"]), ("τ1 [N m]", "τ2 [N m]")),
])
def test_the_signal_figures_plot_each_quantity_against_time_with_the_metric_window_dotted(figures, tmp_path, index,
                                                                                          values, labels):
    """errors.png: e = x_d - x per axis in mm; torques.png: τ1 and τ2 in N m; each panel against
    t, with a dotted line at each edge of the scene's metric window; the time label under the
    lowest panel only and the title over the top one.  Catches the error's sign, the scale, an
    axis or drive swapped, the window's edges and the labels on the wrong panel."""
    c = _columns()
    plot_run(SCENE, c, tmp_path)
    top, bottom = figures[index].axes
    for ax, series, label in zip((top, bottom), values(c), labels):
        signal, *edges = ax.lines
        assert np.array_equal(_xy(signal)[0], c["t"]) and np.array_equal(_xy(signal)[1], series), label
        assert ax.get_ylabel() == label
        assert [tuple(_xy(edge)[0]) for edge in edges] == [(w, w) for w in SCENE.window]
        assert all(edge.get_linestyle() == ":" for edge in edges)
    assert (top.get_xlabel(), bottom.get_xlabel()) == ("", "t [s]")
    assert top.get_title() == f"{SCENE.name} (dotted: metric window)" and bottom.get_title() == ""


def test_the_figures_keep_their_drawn_style_size_and_resolution(figures, tmp_path):
    """The path: the reference dashed black under the end effector solid in the first colour, both
    at the same thin width 1 (the dash and the colour tell them apart, not the weight), a legend
    naming both, equal axes (a circle stays round); the signal panels: each signal at width 0.8
    on a light grid, the window's edges grey (0.6) at width 0.6, thinner than the signal.  Each
    file 120 dpi, the path 5 x 5 in, the signal figures 7 x 5 in, sharing the time axis.  Seed
    4101 [133] (the reference drawn at width 2 went unseen) and its siblings: any width, colour,
    line style, size or resolution changed."""
    from matplotlib.colors import to_rgba
    from PIL import Image

    files = plot_run(SCENE, _columns(), tmp_path)
    (ax,) = figures[0].axes
    reference, effector = ax.lines
    assert (reference.get_linestyle(), to_rgba(reference.get_color())) == ("--", to_rgba("k"))
    assert (effector.get_linestyle(), to_rgba(effector.get_color())) == ("-", to_rgba("C0"))
    assert reference.get_linewidth() == effector.get_linewidth() == 1.0
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["reference", "end effector"]
    assert ax.get_aspect() == 1.0
    assert tuple(figures[0].get_size_inches()) == (5.0, 5.0)
    for fig in figures[1:]:
        assert tuple(fig.get_size_inches()) == (7.0, 5.0)
        top, bottom = fig.axes
        assert top.get_shared_x_axes().joined(top, bottom)
        for panel in (top, bottom):
            signal, *edges = panel.lines
            assert signal.get_linewidth() == 0.8 and signal.get_linestyle() == "-"
            assert all(e.get_linewidth() == 0.6 and to_rgba(e.get_color()) == to_rgba("0.6") for e in edges)
            assert all(line.get_visible() for line in panel.get_xgridlines() + panel.get_ygridlines())
            assert panel.get_xgridlines()[0].get_alpha() == 0.3
    for f in files:   # PNG stores whole pixels per metre: 120 dpi is 4724 px/m, read back as 119.99 dpi
        with Image.open(f) as image:
            assert image.info["dpi"] == pytest.approx((120, 120), abs=0.0254), f.name
