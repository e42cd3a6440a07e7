"""scenarios/batch/sweep_plots.py on made-up sweeps: each group's box (median, quartiles, the 5-95 %
whiskers) and violin read back from the axes against numpy's percentiles of that group's
completed, finite values only; a group of one value gets a box and no violin, an empty group
neither; the panels' order, titles and log scale (issue 31: the scenarios' weakest area; every
plotted value read back)."""
from __future__ import annotations

import math
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

from scenarios.batch import sweep_plots

matplotlib.use("Agg")


def _rows(values, failed=()):
    """Rows of completed runs with ``values`` as every metric (scaled per metric), then runs that
    stopped, with values that must not count."""
    rows = [{"completed": True, "e_ef_mm": v, "tau_ef_Nm": 10.0 * v, "e_ss_mm": v + 1.0} for v in values]
    rows += [{"completed": False, "e_ef_mm": v, "tau_ef_Nm": v, "e_ss_mm": v} for v in failed]
    return rows


@pytest.fixture
def kept(monkeypatch):
    import matplotlib.pyplot as plt

    figures = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: figures.append(fig) or close(fig))
    return figures


def _levels(ax, position):
    """The heights of the box-plot lines drawn at ``position``: the horizontal ones (median,
    caps) and those of the box's outline (quartiles)."""
    levels = set()
    for line in ax.lines:
        x, y = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
        if len(x) and np.all(np.abs(x - position) < 0.2) and (np.ptp(y) == 0.0 or len(y) == 5):
            levels.update(y.tolist())
    return levels


def _wanted(data):
    """Median, quartiles, and the whiskers' ends: the extreme values within the 5-95 % percentiles
    (matplotlib's rule for ``whis=(5, 95)``), by numpy."""
    p5, q1, median, q3, p95 = np.percentile(data, [5, 25, 50, 75, 95])
    return {median, q1, q3, float(data[data >= p5].min()), float(data[data <= p95].max())}


def _violin_spans(ax):
    return sorted((float(p.get_paths()[0].vertices[:, 0].mean().round()),
                   float(p.get_paths()[0].vertices[:, 1].min()), float(p.get_paths()[0].vertices[:, 1].max()))
                  for p in ax.collections)


def test_each_group_is_drawn_at_its_place_from_its_completed_finite_values(kept, tmp_path):
    """Three groups: twenty values (with a stopped run and a NaN left out), none, one value.
    Catches a stopped run's or a NaN's value counted, groups drawn at each other's places, the
    whiskers at other percentiles than 5 and 95, a violin for a single value, and the log
    scale on the wrong metric."""
    rng = np.random.default_rng(5)
    many = list(rng.lognormal(0.0, 0.5, 20))
    groups = {"A": _rows(many + [math.nan], failed=[1e3]), "B": _rows([], failed=[7.0]), "C": _rows([2.5])}
    path = sweep_plots.plot_groups({"strategies": groups}, tmp_path / "groups.png")
    assert path == tmp_path / "groups.png" and path.stat().st_size > 0
    e_ef, tau = kept[0].axes
    assert e_ef.get_yscale() == "log" and tau.get_yscale() == "linear"
    assert e_ef.get_title() == "strategies: e_ef [mm]" and tau.get_title() == "strategies: τ_ef [N m]"
    assert [t.get_text() for t in e_ef.get_xticklabels()] == ["A", "B", "C"]
    for ax, scale in ((e_ef, 1.0), (tau, 10.0)):
        data = scale * np.array(many)
        assert _levels(ax, 0) == _wanted(data), ax.get_title()
        assert _levels(ax, 1) == set() and _levels(ax, 2) == {2.5 * scale}
        (centre, low, high), = _violin_spans(ax)        # one violin: group A's
        assert centre == 0.0 and low == pytest.approx(data.min(), rel=1e-12) and high == pytest.approx(data.max(), rel=1e-12)


def test_one_sweep_is_three_panels_of_its_rows_titled_with_its_settings(kept, tmp_path):
    """Catches a metric's panel missing or of another metric, the title's uncertainty,
    distribution, seed or count of samples wrong."""
    values = [0.5, 1.0, 1.5, 2.0, 4.0]
    sweep = SimpleNamespace(scene="bench_x", rows=_rows(values, failed=[9.0]),
                            settings={"uncertainty": 0.05, "distribution": "uniform", "seed": 7})
    sweep_plots.plot_sweep(sweep, tmp_path / "sweep.png")
    fig = kept[0]
    assert fig._suptitle.get_text() == "bench_x: 6 samples, U = 0.05 (uniform), seed 7"
    for ax, (metric, label), shift, scale in zip(fig.axes, sweep_plots._LABELS.items(), (0.0, 0.0, 1.0),
                                                 (1.0, 10.0, 1.0)):
        data = scale * np.array(values) + shift
        assert ax.get_ylabel() == label and [t.get_text() for t in ax.get_xticklabels()] == ["bench_x"]
        assert _levels(ax, 0) == _wanted(data), metric


def test_each_row_of_panels_keeps_its_height_and_order_as_rows_are_added(kept, tmp_path):
    """Catches a figure of fixed height (its rows squashed as panels are added) and rows drawn
    out of the panels' order: the panels of a three-row figure are as tall, in inches, as those
    of a one-row figure, and top to bottom in the order given."""
    groups = {"A": _rows([1.0, 2.0, 3.0]), "B": _rows([2.0, 4.0])}

    def heights(fig):
        return [ax.get_position().height * fig.get_size_inches()[1] for ax in fig.axes]

    sweep_plots.plot_groups({"one": groups}, tmp_path / "one.png")
    sweep_plots.plot_groups({"first": groups, "second": groups, "third": groups}, tmp_path / "three.png")
    one, three = kept
    assert len(three.axes) == 6
    assert heights(three) == pytest.approx([heights(one)[0]] * 6, rel=0.15)
    rows = [ax for ax in three.axes if ax.get_title().endswith("e_ef [mm]")]
    assert [ax.get_title().split(":")[0] for ax in rows] == ["first", "second", "third"]
    assert [ax.get_position().y0 for ax in rows] == sorted((ax.get_position().y0 for ax in rows), reverse=True)


@pytest.mark.parametrize("n, rotation", [(1, 0.0), (4, 0.0), (5, 30.0), (8, 30.0)])
def test_the_tick_labels_are_the_groups_slanted_past_four(n, rotation, kept, tmp_path):
    """Every panel's tick labels are the group names in order, upright up to four groups and
    slanted by 30° from five (the docstring).  Catches the threshold moved by one, the angle
    changed, labels out of order."""
    names = [f"G{k}" for k in range(n)]
    sweep_plots.plot_groups({"p": {name: _rows([1.0 + k, 2.0 + k]) for k, name in enumerate(names)}},
                            tmp_path / "g.png")
    for ax in kept[0].axes:
        labels = ax.get_xticklabels()
        assert [t.get_text() for t in labels] == names
        assert {t.get_rotation() for t in labels} == {rotation}


def test_the_panels_have_horizontal_grid_lines_only_as_faint_as_the_run_figures(kept, tmp_path):
    """The metric's levels are read off horizontal grid lines (no vertical ones between the
    groups), drawn as faint as those of ``parcosim run``'s figures (scenarios/run/runner.py,
    rendered here): one grid style across the scenarios' figures.  Catches the vertical grid
    drawn, the grid dropped, or a heavier grid than the other figures' (seed 3901 [261])."""
    from dataclasses import replace

    from scenarios.run import runner
    from scenarios.scenes import get_scene

    t = np.arange(5) * 0.01
    runner.plot_run(replace(get_scene("bench_circle_PDq"), window=(0.01, 0.03)),
                    {"t": t, "x": t, "y": t, "x_d": t, "y_d": t, "tau1": t, "tau2": t}, tmp_path)
    run_alphas = {line.get_alpha() for fig in kept for ax in fig.axes for line in ax.yaxis.get_gridlines()
                  if line.get_visible()}                     # the time series' panels (the path has none)
    (run_alpha,) = run_alphas
    assert run_alpha is not None and run_alpha < 1.0
    before = len(kept)
    sweep = SimpleNamespace(scene="bench_x", rows=_rows([0.5, 1.0, 2.0]),
                            settings={"uncertainty": 0.05, "distribution": "uniform", "seed": 7})
    sweep_plots.plot_sweep(sweep, tmp_path / "sweep.png")
    sweep_plots.plot_groups({"strategies": {"A": _rows([1.0, 2.0]), "B": _rows([3.0])}}, tmp_path / "groups.png")
    axes = [ax for fig in kept[before:] for ax in fig.axes]
    assert len(axes) == 5
    for ax in axes:
        assert all(line.get_visible() and line.get_alpha() == run_alpha for line in ax.yaxis.get_gridlines())
        assert not any(line.get_visible() for line in ax.xaxis.get_gridlines()), ax.get_title()
