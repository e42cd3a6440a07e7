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
