"""scenarios/scenes/run/metrics.py's ``scene_metrics`` on synthetic columns at a 2 ms sample,
every metric compared with its definition (7.31-7.32, the module docstring) written again here
as plain loops over the samples (issue 31: a second sample time; errors with a non-zero mean,
so a sign or a swapped axis shows; each value read against an independent computation)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from scenarios.run.metrics import SETTLE_BAND, SETTLE_HOLD, scene_metrics
from scenarios.scenes import get_scene
from scenarios.scenes.scene import STEADY_STATE_WINDOW
from scenarios.scenes.transforms import with_sample_time

H = 2e-3


def _scene(stop_time=None):
    """bench_circle_TCMDx at 2 ms: window [1, 8] s, the reference stops at 8 s, run to 11 s."""
    scene = with_sample_time(get_scene("bench_circle_TCMDx"), H)
    if stop_time is not None:
        scene = replace(scene, system=replace(scene.system, stop_time=stop_time))
    return scene


def _columns(end=11.0):
    """Errors x_d - x and y_d - y with different means and shapes on each axis, a transient
    after the stop at 8 s that decays into a final offset, and torques of unequal size."""
    k = np.arange(int(round(end / H)) + 1)
    # a master's times are k H within rounding (sums t + h, whole nanoseconds): here 0.3 ps late
    # at 8, 9, 10 and 11 s (the ends of the windows), 0.3 ps early on every other sample (their starts)
    t = k * H + np.where((k % 500 == 0) & (k >= 4000), 3e-13, -3e-13)
    after = np.clip(t - 8.0, 0.0, None)
    ex = 3e-4 + 2e-4 * np.sin(5.0 * t) * (t < 8.0) + 8e-4 * np.exp(-after / 0.15) * (t >= 8.0)
    ey = -1e-4 + 1e-4 * np.cos(3.0 * t) * (t < 8.0) - 5e-4 * np.exp(-after / 0.3) * (t >= 8.0)
    x, y = 0.01 * np.cos(t), 0.1 + 0.01 * np.sin(t)
    return {"t": t, "x": x, "y": y, "x_d": x + ex, "y_d": y + ey,
            "tau1": 0.02 * np.sin(t) + 0.005, "tau2": -0.03 * np.cos(2 * t)}


def _rms(pairs):
    pairs = list(pairs)
    return math.sqrt(sum(a * a + b * b for a, b in pairs) / len(pairs))


def test_every_metric_is_its_definition_over_its_samples():
    """Catches: the window's ends (inclusive) or the error's sign or axes mixed up; tau_ef of
    the wrong columns; e_ss over the wrong samples (the settling time found as the first
    sample after the last one outside the band around the final mean); e_ss_x/y's means;
    e_ss_1s's window [stop + 0.8, stop + 1] s; e_max; the real-time factor's quotient."""
    c = _columns()
    m = scene_metrics(_scene(), c, wall_s=2.5, completed=True, init_s=0.25)
    t = c["t"].tolist()
    assert t[4000] > 8.0 and t[500] < 1.0 and t[4500] > 9.0 and t[4400] < 8.8     # the windows' ends, 0.3 ps off
    ex = [a - b for a, b in zip(c["x_d"], c["x"])]
    ey = [a - b for a, b in zip(c["y_d"], c["y"])]
    window = range(500, 4001)                              # [1, 8] s by sample index: k H
    assert m["e_ef_mm"] == pytest.approx(1e3 * _rms((ex[k], ey[k]) for k in window), rel=1e-12)
    assert m["tau_ef_Nm"] == pytest.approx(_rms((c["tau1"][k], c["tau2"][k]) for k in window), rel=1e-12)
    last = range(5500 - int(round(STEADY_STATE_WINDOW / H)), 5501)
    fx, fy = sum(ex[k] for k in last) / len(last), sum(ey[k] for k in last) / len(last)
    k_settle = next(k for k in range(len(t) - 1, -1, -1)
                    if t[k] >= 8.0 and math.hypot(ex[k] - fx, ey[k] - fy) > SETTLE_BAND) + 1
    assert m["settled"] is True and t[-1] - t[k_settle] >= SETTLE_HOLD
    assert m["t_settle_s"] == pytest.approx(t[k_settle] - 8.0, abs=1e-12)
    assert 0.3 < m["t_settle_s"] < 1.0                                   # the transient is there
    tail = range(k_settle, len(t))
    assert m["e_ss_mm"] == pytest.approx(1e3 * _rms((ex[k], ey[k]) for k in tail), rel=1e-12)
    assert m["e_ss_x_mm"] == pytest.approx(1e3 * sum(ex[k] for k in tail) / len(tail), rel=1e-12)
    assert m["e_ss_y_mm"] == pytest.approx(1e3 * sum(ey[k] for k in tail) / len(tail), rel=1e-12)
    assert m["e_ss_x_mm"] > 0.29 and m["e_ss_y_mm"] < -0.09                # signs: x_d - x, y_d - y
    at_1s = range(4400, 4501)                              # [stop + 0.8, stop + 1] s
    assert m["e_ss_1s_mm"] == pytest.approx(1e3 * _rms((ex[k], ey[k]) for k in at_1s), rel=1e-12)
    assert m["e_max_mm"] == pytest.approx(1e3 * max(math.hypot(a, b) for a, b in zip(ex, ey)), rel=1e-12)
    assert m["simulated_s"] == t[-1] and m["wall_s"] == 2.5 and m["init_s"] == 0.25
    assert m["realtime_factor"] == pytest.approx(11.0 / 2.5, rel=1e-13)
    assert m["window_s"] == [1.0, 8.0] and m["completed"] is True
    assert m["scene"] == "bench_circle_TCMDx" and m["strategy"] == "TCMDx"


def test_a_run_that_stops_before_the_window_ends_gives_nan_not_a_shorter_average():
    """Stopped at 5 s (inside [1, 8]): e_ef, tau_ef and every steady-state value NaN, e_max
    and the simulated time those of the samples there are.  Catches the "reached" test
    dropped or turned round."""
    c = {k: v[: int(round(5.0 / H)) + 1] for k, v in _columns().items()}
    m = scene_metrics(_scene(), c, wall_s=1.0, completed=False)
    for key in ("e_ef_mm", "tau_ef_Nm", "e_ss_mm", "e_ss_x_mm", "e_ss_y_mm", "t_settle_s", "e_ss_1s_mm"):
        assert math.isnan(m[key]), key
    assert m["settled"] is False and m["completed"] is False and m["simulated_s"] == pytest.approx(5.0, abs=1e-12)
    ex, ey = c["x_d"] - c["x"], c["y_d"] - c["y"]
    assert m["e_max_mm"] == pytest.approx(1e3 * max(math.hypot(a, b) for a, b in zip(ex, ey)), rel=1e-12)


def test_e_ss_1s_needs_the_run_to_reach_one_second_after_the_stop():
    """The scene run to 8.9 s: e_ss is there (over the run's last 0.2 s, not settled: the
    transient lasts past the end) but e_ss_1s is NaN, its window [8.8, 9] s not being whole.
    Catches ``end >= stop + E_SS_1S`` with the wrong sign or constant."""
    c = _columns(end=8.9)
    m = scene_metrics(_scene(stop_time=8.9), c, wall_s=1.0, completed=True)
    assert math.isnan(m["e_ss_1s_mm"]) and m["settled"] is False and math.isnan(m["t_settle_s"])
    t = c["t"]
    last = slice(4450 - int(round(STEADY_STATE_WINDOW / H)), 4451)
    ex, ey = (c["x_d"] - c["x"])[last], (c["y_d"] - c["y"])[last]
    assert m["e_ss_mm"] == pytest.approx(1e3 * _rms(zip(ex, ey)), rel=1e-12)
    assert m["e_ss_x_mm"] == pytest.approx(1e3 * sum(ex) / len(ex), rel=1e-12)


@pytest.mark.parametrize("name, sides", [("bench_circle_TCMDx", None), ("bench_triangle_TCMDx", 3)])
def test_a_run_without_a_single_row_has_no_metric_and_no_simulated_time(name, sides):
    """A run stopped before its first row (a refusal at initialisation): every error and the
    steady state NaN (a triangle's three sides too), nothing settled, 0 s simulated, a real-time
    factor of 0 over a wall time and NaN over none, the given times and the scene's own names
    and window kept.  Catches a default other than 0 s for the simulated time (a run that never
    started counted as having run), an empty mean taken as 0, a division by a zero wall time."""
    scene = get_scene(name)
    empty = {k: np.empty(0) for k in ("t", "x", "y", "x_d", "y_d", "tau1", "tau2")}
    m = scene_metrics(scene, empty, wall_s=0.5, completed=False, init_s=0.125)
    for key in ("e_ef_mm", "tau_ef_Nm", "e_ss_mm", "e_ss_x_mm", "e_ss_y_mm", "t_settle_s", "e_ss_1s_mm", "e_max_mm"):
        assert math.isnan(m[key]), key
    assert (m["simulated_s"], m["wall_s"], m["init_s"], m["realtime_factor"]) == (0.0, 0.5, 0.125, 0.0)
    assert m["settled"] is False and m["completed"] is False
    assert (m["scene"], m["strategy"], m["window_s"]) == (name, scene.strategy, list(scene.window))
    assert ("e_contour_sides_mm" in m) == (sides is not None)
    if sides:
        assert len(m["e_contour_sides_mm"]) == sides and all(math.isnan(e) for e in m["e_contour_sides_mm"])
    assert math.isnan(scene_metrics(scene, empty, wall_s=0.0, completed=False)["realtime_factor"])
