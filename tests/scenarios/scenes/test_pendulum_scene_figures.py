"""scenarios/scenes/pendulum.py's figures and run line on made-up columns: every plotted line read
back from the figures (the pitch in degrees, the wheels, voltages and, when the drives are
modelled, currents against time; the axle's path and its reference in mm), the path's square
window (at least 10 cm, centred on both curves), and ``pendulum_line``'s figures (issue 31: the
scenarios' weakest area; every plotted value read back)."""
from __future__ import annotations

from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

from scenarios.scenes.pendulum import BALANCED_DEG, pendulum_line, plot_pendulum

matplotlib.use("Agg")


def _columns(currents: bool) -> dict:
    t = np.arange(51) * 2e-3
    c = {"t": t, "psi": 0.05 * np.cos(9 * t), "psi_hat": 0.048 * np.cos(9 * t) + 0.001, "omega_l": 3 * t,
         "omega_r": -2 * t, "v_l": 1.5 * np.sin(t), "v_r": -0.5 + t, "x": 0.3 * t + 0.01, "y": 0.02 * t ** 2,
         "x_d": 0.25 * t, "y_d": np.zeros_like(t)}
    if currents:
        c.update(i_l=0.2 * t, i_r=-0.1 - t)
    return c


@pytest.fixture
def kept(monkeypatch):
    import matplotlib.pyplot as plt

    figures, close = [], plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: figures.append(fig) or close(fig))
    return figures


def _lines(ax):
    return [(line.get_label(), np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float))
            for line in ax.lines]


@pytest.mark.parametrize("currents", [False, True])
def test_each_figure_plots_its_signals_against_time_in_their_units(kept, tmp_path, currents):
    """Catches the pitch left in radians, a signal on another panel or of the other wheel, the
    current panel missing when the drives are modelled (or drawn without them), and the path
    in metres."""
    c = _columns(currents)
    files = plot_pendulum(SimpleNamespace(name="pend"), c, tmp_path)
    assert [f.name for f in files] == ["pitch.png", "wheel_speeds.png", "voltages.png", "path.png"]
    assert all(f.parent == tmp_path and f.stat().st_size > 0 for f in files)
    pitch, wheels, volts, path = kept
    expected = {0: [[("psi", np.degrees(c["psi"])), ("psi_hat", np.degrees(c["psi_hat"]))]],
                1: [[("omega_l", c["omega_l"])], [("omega_r", c["omega_r"])]],
                2: [[("v_l", c["v_l"]), ("v_r", c["v_r"])]] + ([[("i_l", c["i_l"]), ("i_r", c["i_r"])]] if currents else [])}
    for fig, panels in zip((pitch, wheels, volts), expected.values()):
        assert len(fig.axes) == len(panels) and fig.axes[0].get_title() == "pend"
        for ax, wanted in zip(fig.axes, panels):
            got = _lines(ax)
            assert [g[0] for g in got] == [w[0] for w in wanted]
            for (_, x, y), (key, values) in zip(got, wanted):
                assert np.array_equal(x, c["t"]) and np.array_equal(y, values), key
    (ref, xr, yr), (axle, xa, ya) = _lines(path.axes[0])
    assert (ref, axle) == ("reference", "axle")
    assert np.array_equal(xr, 1e3 * c["x_d"]) and np.array_equal(yr, 1e3 * c["y_d"])
    assert np.array_equal(xa, 1e3 * c["x"]) and np.array_equal(ya, 1e3 * c["y"])


def test_the_path_window_is_square_centred_and_at_least_10_cm(kept, tmp_path, monkeypatch):
    """Catches the window not centred on both curves, a side below 100 mm for a scene that
    hardly moves, and a wide path cut off.  (The files are not drawn here: the limits do not
    depend on them.)"""
    from matplotlib.figure import Figure

    monkeypatch.setattr(Figure, "savefig", lambda self, path, **kwargs: None)
    c = _columns(False)
    plot_pendulum(SimpleNamespace(name="pend"), c, tmp_path)
    ax = kept[-1].axes[0]
    xs, ys = 1e3 * np.concatenate([c["x"], c["x_d"]]), 1e3 * np.concatenate([c["y"], c["y_d"]])
    cx, cy = 0.5 * (xs.min() + xs.max()), 0.5 * (ys.min() + ys.max())
    assert ax.get_xlim() == pytest.approx((cx - 50.0, cx + 50.0), abs=1e-12)
    assert ax.get_ylim() == pytest.approx((cy - 50.0, cy + 50.0), abs=1e-12)
    wide = dict(c, x=10 * c["x"])                      # 0.3 m to 3.01 m wide: 0.55 x its span each side
    plot_pendulum(SimpleNamespace(name="pend"), wide, tmp_path)
    ax = kept[-1].axes[0]
    xs = 1e3 * np.concatenate([wide["x"], wide["x_d"]])
    half = 0.55 * np.ptp(xs)
    assert half > 50.0 and ax.get_xlim() == pytest.approx((0.5 * (xs.min() + xs.max()) - half,
                                                           0.5 * (xs.min() + xs.max()) + half), abs=1e-9)


def test_the_run_line_states_the_peaks_and_whether_it_settled():
    """Catches the settling time or the last second's pitch of another key, and an unsettled
    run said to have settled."""
    m = {"peak_pitch_deg": 4.56789, "last_second_pitch_deg": 0.0123456, "final_position_error_mm": 12.3456,
         "settling_time_s": 1.23456}
    assert pendulum_line(m) == (f"pitch peak 4.57 deg, last second 0.0123 deg (settled within {BALANCED_DEG:g} deg "
                                "at 1.23 s), final position error 12.3 mm")
    assert pendulum_line({**m, "settling_time_s": float("nan")}).endswith(
        f"(not within {BALANCED_DEG:g} deg at the end), final position error 12.3 mm")


def test_a_path_tall_in_y_sets_both_sides_from_its_height(kept, tmp_path, monkeypatch):
    """A path 0.5 m tall and 30 mm wide: both limits are 0.55 x the height each side of their own
    centres (the window stays square).  Catches the half-width taken from x alone and either
    centre taken from the other axis.  (Files not drawn: the limits do not depend on them.)"""
    from matplotlib.figure import Figure

    monkeypatch.setattr(Figure, "savefig", lambda self, path, **kwargs: None)
    c = _columns(False)
    tall = dict(c, y=5.0 * c["t"] + 0.2, y_d=5.0 * c["t"] + 0.21)   # 0.2 m to 0.71 m
    plot_pendulum(SimpleNamespace(name="pend"), tall, tmp_path)
    ax = kept[-1].axes[0]
    xs, ys = 1e3 * np.concatenate([tall["x"], tall["x_d"]]), 1e3 * np.concatenate([tall["y"], tall["y_d"]])
    half = 0.55 * (ys.max() - ys.min())
    cx, cy = 0.5 * (xs.min() + xs.max()), 0.5 * (ys.min() + ys.max())
    assert half > 50.0 > 0.55 * (xs.max() - xs.min())
    assert ax.get_xlim() == pytest.approx((cx - half, cx + half), abs=1e-9)
    assert ax.get_ylim() == pytest.approx((cy - half, cy + half), abs=1e-9)
