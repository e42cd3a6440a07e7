"""Where a polygon's error lies (scenarios.run.metrics.side_contour_errors): synthetic paths with a
known distance from each side, a pure lag along the path, samples outside the sides' times,
and the scenes' own polygon (scenarios.run.metrics.scene_polygon)."""
import math

import numpy as np
import pytest

from controller.trajectories import PolygonTrajectory, triangle
from scenarios.run.metrics import scene_polygon, side_contour_errors
from scenarios.scenes.catalogue import get_scene

H = 1e-3


def _reference(polygon, t):
    samples = [polygon(tk) for tk in t]
    return np.array([s.x for s in samples]), np.array([s.y for s in samples])


def _outward_normals(vertices):
    """Unit normal of each side pointing out of the (convex) polygon."""
    v = np.asarray(vertices, dtype=float)
    centre = v.mean(axis=0)
    normals = []
    for a, b in zip(v, np.roll(v, -1, axis=0)):
        n = np.array([b[1] - a[1], a[0] - b[0]]) / math.hypot(*(b - a))
        normals.append(n if n @ (a - centre) > 0.0 else -n)
    return np.array(normals)


def test_a_path_offset_outward_by_d_on_each_side_gives_d():
    """The reference pushed out of the triangle by 0.3, 1.1 and 2.0 mm on sides I, II, III: outside a
    convex polygon, the nearest point of its path is the foot on the side whose band holds the
    point, so each side's RMS is its offset (the other sides are farther)."""
    polygon = triangle()
    t = np.arange(0.0, polygon.duration + 1.0, H)
    x, y = _reference(polygon, t)
    offsets = np.array([0.3e-3, 1.1e-3, 2.0e-3])
    side = (np.floor(t / polygon.side_time).astype(int) % 3)
    normals = _outward_normals(polygon.vertices)[side]
    moving = t < polygon.duration
    x = x + np.where(moving, offsets[side] * normals[:, 0], 0.05)     # a far point in the hold: not counted
    y = y + np.where(moving, offsets[side] * normals[:, 1], 0.05)
    assert side_contour_errors(polygon, t, x, y) == pytest.approx(offsets, rel=1e-9)


def test_a_lag_along_the_path_is_no_contour_error():
    """The end effector 60 ms behind the reference stays on the path: no contour error, while its
    distance from the reference point is millimetres."""
    polygon = triangle()
    t = np.arange(0.0, polygon.duration, H)
    x, y = _reference(polygon, np.clip(t - 0.06, 0.0, None))
    xd, yd = _reference(polygon, t)
    assert np.sqrt(np.mean((x - xd) ** 2 + (y - yd) ** 2)) > 5e-3
    assert max(side_contour_errors(polygon, t, x, y)) < 1e-12


def test_samples_are_assigned_by_the_time_the_reference_travels_each_side():
    """A square travelled once, 1 s a side: a sample off the path only while the reference is on
    side III counts on side III alone; a run that stopped on side II has no side III (NaN)."""
    square = PolygonTrajectory(vertices=((0.0, 0.0), (0.1, 0.0), (0.1, 0.1), (0.0, 0.1)), side_time=1.0, cycles=1)
    t = np.arange(0.0, 4.0, 0.25)
    x, y = _reference(square, t)
    y = np.where((t >= 2.0) & (t < 3.0), y + 0.002, y)      # side III is the top, y = 0.1: pushed out
    errors = side_contour_errors(square, t, x, y)
    assert max(errors[0], errors[1], errors[3]) < 1e-15 and errors[2] == pytest.approx(0.002, rel=1e-12)
    short = t < 1.6
    stopped = side_contour_errors(square, t[short], x[short], y[short])
    assert max(stopped[:2]) < 1e-15 and math.isnan(stopped[2]) and math.isnan(stopped[3])


def test_the_scene_polygon_is_its_trajectory_component_s():
    """A triangle scene's polygon is the triangle of 7.24-7.27, a circle scene has none."""
    assert scene_polygon(get_scene("bench_triangle_TCq")) == triangle()
    assert scene_polygon(get_scene("bench_circle_TCq")) is None


def test_the_named_sides_must_each_exceed_every_other_side():
    """sides_hold: a claim holds when each named side's error is above every other side's;
    a tie, a named side below another, or a missing value do not hold."""
    from scenarios.batch.report import sides_hold

    assert sides_hold([0.3, 0.1, 0.2], (1,)) and sides_hold([0.3, 0.1, 0.2], (1, 3))
    assert not sides_hold([0.2, 0.3, 0.1], (1,)) and not sides_hold([0.3, 0.25, 0.2], (1, 3))
    assert not sides_hold([0.3, 0.3, 0.1], (1,)) and not sides_hold([0.3, math.nan, 0.1], (1,))


def test_the_side_table_reports_the_larger_side_and_the_count():
    """side_section: one row per strategy with the larger side here and the bench's, and the
    count of strategies whose bench sides hold."""
    from scenarios.batch.report import THESIS_TRIANGLE_SIDES, side_section

    contour = {s: [1.0, 2.0, 3.0] for s in THESIS_TRIANGLE_SIDES}        # side III larger everywhere
    text = "\n".join(side_section(contour))
    assert "| TCq | 1.00 | 2.00 | 3.00 | III | I | no |" in text
    assert "| PDq | 1.00 | 2.00 | 3.00 | III | I and III | no |" in text
    contour["PDx"] = [0.1, 0.5, 0.2]
    contour["PDq"] = [0.4, 0.1, 0.3]
    contour["TCq"] = [0.9, 0.1, None]                                    # a run that stopped on side II
    text = "\n".join(side_section(contour))
    assert "hold here for 2 of 8 strategies" in text and "| TCq | 0.90 | 0.10 | — | I | I | no |" in text


def test_every_round_of_a_polygon_travelled_twice_counts_and_the_hold_after_does_not():
    """A square travelled twice (cycles = 2, 1 s a side): a sample pushed out while the reference
    travels side III of the second round counts on side III (RMS over both rounds' samples of
    that side: d / sqrt(2) with d off in one round of two), a far sample in the hold after the
    last round counts nowhere.  Catches the sides' time taken as one round (``index < n``)
    and the hold counted as a further round."""
    square = PolygonTrajectory(vertices=((0.0, 0.0), (0.1, 0.0), (0.1, 0.1), (0.0, 0.1)), side_time=1.0, cycles=2)
    t = np.arange(0.0, 10.0, 0.25)
    x, y = _reference(square, t)
    d = 0.002
    y = np.where((t >= 6.0) & (t < 7.0), y + d, y)      # round 2, side III (the top): pushed out
    x = np.where(t >= square.duration, x - 0.05, x)      # the hold at (0, 0): 5 cm off, not counted
    errors = side_contour_errors(square, t, x, y)
    assert max(errors[0], errors[1], errors[3]) < 1e-15
    assert errors[2] == pytest.approx(d / math.sqrt(2.0), rel=1e-12)
