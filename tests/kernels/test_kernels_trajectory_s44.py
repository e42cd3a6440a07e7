"""The trajectory kernel (kernels/src/trajectory.c) where its branches switch, met exactly:
a stopping circle at its duration, a polygon at the end of its rounds (vertices whose sums
round, so that "the first vertex" and "the last side at tau = 1" differ in their bits), a
polygon of a single vertex (session 44, training 4411 generalised)."""
from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest

import kernels
from controller import fasttrajectory as F
from controller.trajectories import CircleTrajectory, PolygonTrajectory

_SAMPLE = kernels.function("pc_trajectory_sample", ctypes.c_int, ctypes.c_void_p, ctypes.c_long, ctypes.c_double,
                           ctypes.c_void_p, ctypes.POINTER(kernels.Refusal))
#: The last vertex plus (first - last) rounds away from the first vertex's x (0.1 + 0.6 != 0.1 in floats...).
VERTICES = ((0.1, 0.7), (0.3, -0.2), (-0.45, 0.35))


def _sample(buf, t):
    out, refusal = np.zeros(6), kernels.Refusal()
    code = _SAMPLE(kernels.address(buf), buf.size, t, kernels.address(out), refusal)
    return code, refusal, out


def test_the_vertices_make_the_last_side_at_its_end_differ_from_the_first_vertex():
    """The premise of the next test: last + (first - last) is not first, in floats."""
    (x0, y0), (xl, yl) = VERTICES[0], VERTICES[-1]
    assert xl + (x0 - xl) * 1.0 != x0


@pytest.mark.parametrize("cycles", [1, 3])
def test_a_polygon_holds_its_first_vertex_at_rest_from_the_end_of_its_rounds_exactly(cycles):
    """CircleTrajectory/PolygonTrajectory: after ``cycles`` rounds the first vertex is held at
    rest; at t = rounds x sides x side_time exactly, the output is the first vertex's words bit
    for bit and zero velocity and acceleration (``t >= end``; ``t > end`` would evaluate the
    last side at tau = 1, whose position is the vertex only to rounding); a double before the
    end, the last side still moving toward it."""
    side_time = 0.25
    polygon = PolygonTrajectory(vertices=VERTICES, side_time=side_time, cycles=cycles)
    end = cycles * len(VERTICES) * side_time
    code, _, out = _sample(polygon.buf, end)
    assert code == F.OK and out.tolist() == [*VERTICES[0], 0.0, 0.0, 0.0, 0.0]
    code, _, out = _sample(polygon.buf, end - 0.5 * side_time)     # half way along the last side
    mid = np.add(VERTICES[-1], VERTICES[0]) / 2
    assert code == F.OK and out[:2] == pytest.approx(mid, abs=1e-15) and np.abs(out[2:4]).max() > 0.1


def test_a_polygon_of_one_vertex_holds_it_and_none_is_refused():
    """trajectory.c's whole(vertices, MAX): one vertex is the smallest polygon (its sides go
    from the vertex to itself: it stays there, at rest); 0 vertices is refused as BAD_LAYOUT
    naming the vertices word."""
    polygon = PolygonTrajectory(vertices=((0.125, -0.375),), side_time=0.5, cycles=2)
    for t in (0.0, 0.3, 0.5, 0.99, 1.0, 7.0):
        code, _, out = _sample(polygon.buf, t)
        assert code == F.OK and out.tolist() == [0.125, -0.375, 0.0, 0.0, 0.0, 0.0], t
    buf = polygon.buf.copy()
    buf[F.T_VERTICES] = 0.0
    code, refusal, out = _sample(buf, 0.3)
    assert (code, refusal.index, refusal.value) == (F.BAD_LAYOUT, F.T_VERTICES, 0.0) and not out.any()


@pytest.mark.parametrize("stops", [True, False])
def test_a_stopping_circle_is_at_rest_from_its_duration_exactly(stops):
    """CircleTrajectory's ``stops``: the reference holds the point reached at ``duration``
    afterwards, velocity and acceleration 0, from t = duration itself (``t >= duration``); a
    double before it, it still moves at r w.  One that does not stop moves at its duration."""
    w, r, duration = 2.0, 0.05, 1.5
    trajectory = CircleTrajectory(center=(0.0, 0.1), radius=r, initial_angle=0.25, angular_velocity=w,
                                  duration=duration, stops=stops, start_point=(0.0, 0.0))
    angle = 0.25 + w * duration
    code, _, out = _sample(trajectory.buf, duration)
    assert code == F.OK
    assert out[:2] == pytest.approx((r * math.cos(angle), 0.1 + r * math.sin(angle)), abs=1e-15)
    speed = math.hypot(out[2], out[3])
    assert speed == (0.0 if stops else pytest.approx(r * w, rel=1e-12))
    code, _, out = _sample(trajectory.buf, math.nextafter(duration, 0.0))
    assert math.hypot(out[2], out[3]) == pytest.approx(r * w, rel=1e-12)
    assert math.hypot(out[4], out[5]) == pytest.approx(r * w * w, rel=1e-12)
