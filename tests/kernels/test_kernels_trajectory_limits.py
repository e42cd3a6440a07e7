"""The trajectory kernel (kernels/src/trajectory.c) at the limits of what it accepts: the most
rounds of a polygon, a buffer exactly long enough for its vertices, a circle that does not stop
sampled long after its duration.  Checked against the layout (trajectory.h) and the circle's
formula (7.18), not against a run."""
from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest

import kernels
from controller import fasttrajectory as F
from controller.trajectories import PolygonTrajectory, thesis_circle

_SAMPLE = kernels.function("pc_trajectory_sample", ctypes.c_int, ctypes.c_void_p, ctypes.c_long, ctypes.c_double,
                           ctypes.c_void_p, ctypes.POINTER(kernels.Refusal))
SQUARE = ((0.0, 0.0), (0.5, 0.0), (0.5, 0.5), (0.0, 0.5))


def _sample(buf, t, words=None):
    out, refusal = np.zeros(6), kernels.Refusal()
    code = _SAMPLE(kernels.address(buf), buf.size if words is None else words, t, kernels.address(out), refusal)
    return code, refusal, out


def test_the_most_rounds_are_the_documented_million():
    """trajectory.h: PC_TRAJECTORY_MAX_CYCLES = 1000000, read by the Python layer."""
    assert F.MAX_CYCLES == 1000000


def test_a_polygon_of_the_most_rounds_is_sampled_and_one_more_round_is_refused():
    """Catches ``<`` for ``<=`` in the kernel's whole-number check of ``cycles``: MAX_CYCLES rounds
    of a square (1/4 s sides) are sampled (at t = 1/8 s half way along the first side, a smooth
    step is symmetric: the midpoint), one round more is refused naming the cycles word."""
    square = PolygonTrajectory(vertices=SQUARE, side_time=0.25, cycles=F.MAX_CYCLES)
    code, _, out = _sample(square.buf, 0.125)
    assert code == F.OK
    assert out[:2] == pytest.approx((0.25, 0.0), abs=1e-15)
    buf = square.buf.copy()
    buf[F.T_CYCLES] = F.MAX_CYCLES + 1
    code, refusal, out = _sample(buf, 0.125)
    assert (code, refusal.index, refusal.value) == (F.BAD_LAYOUT, F.T_CYCLES, F.MAX_CYCLES + 1)
    assert not out.any()


def test_a_polygon_buffer_one_word_short_of_its_vertices_is_refused():
    """The buffer holds T_POINTS words then two per vertex: exactly that many is sampled, one
    word fewer (the last vertex's y missing) is refused naming the vertices word."""
    square = PolygonTrajectory(vertices=SQUARE, side_time=0.25, cycles=1)
    assert square.buf.size == F.T_POINTS + 2 * len(SQUARE)
    assert _sample(square.buf, 0.6)[0] == F.OK
    code, refusal, _ = _sample(square.buf, 0.6, words=square.buf.size - 1)
    assert (code, refusal.index, refusal.value) == (F.BAD_LAYOUT, F.T_VERTICES, 4.0)


def test_a_polygon_reaches_each_vertex_after_each_side_and_then_holds_the_first():
    """Side i runs from vertex i to vertex i + 1 (the last back to the first); at the end of the
    rounds the first vertex is held at rest."""
    square = PolygonTrajectory(vertices=SQUARE, side_time=0.25, cycles=2)
    for k in range(8):
        code, _, out = _sample(square.buf, 0.25 * k)
        assert code == F.OK and tuple(out[:2]) == pytest.approx(SQUARE[k % 4], abs=1e-15), k
        # half way along side k: the midpoint of vertices k and k + 1
        mid = np.add(SQUARE[k % 4], SQUARE[(k + 1) % 4]) / 2
        code, _, out = _sample(square.buf, 0.25 * k + 0.125)
        assert tuple(out[:2]) == pytest.approx(tuple(mid), abs=1e-15), k
    code, _, out = _sample(square.buf, 2.0)
    assert code == F.OK and tuple(out) == (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def test_a_circle_that_does_not_stop_keeps_circling_after_its_duration():
    """The thesis circle (stops false) at t = 2 durations + 0.3 s is still the analytic motion
    (7.18): position, velocity r w, centripetal acceleration r w^2."""
    trajectory = thesis_circle()
    t = 2 * trajectory.duration + 0.3
    phi, r, w = 2 * math.pi * t, 0.07, 2 * math.pi
    expected = (r * math.cos(phi), 0.17 + r * math.sin(phi), -r * w * math.sin(phi), r * w * math.cos(phi),
                -r * w * w * math.cos(phi), -r * w * w * math.sin(phi))
    np.testing.assert_allclose(tuple(trajectory(t)), expected, rtol=1e-9, atol=1e-12)


def _all_kinds():
    from controller.trajectories import hold

    return {"circle": thesis_circle().buf, "polygon": PolygonTrajectory(SQUARE, 0.25, 1).buf, "hold": hold().buf}


@pytest.mark.parametrize("kind", ["circle", "polygon", "hold"])
def test_time_zero_is_sampled_and_any_time_before_it_refused(kind):
    """pc_trajectory_sample takes t >= 0: t = 0 is sampled; the largest negative double and NaN
    are refused as BAD_TIME, index 0, with the time as value, the output left untouched."""
    buf = _all_kinds()[kind]
    assert _sample(buf, 0.0)[0] == F.OK
    for t in (-5e-324, float("nan")):
        code, refusal, out = _sample(buf, t)
        assert (code, refusal.index) == (F.BAD_TIME, 0)
        assert refusal.value == t or (math.isnan(t) and math.isnan(refusal.value))
        assert not out.any()


@pytest.mark.parametrize("kind, size", [("circle", F.T_STOPS + 1), ("polygon", F.T_POINTS), ("hold", F.T_HOLD_Y + 1)])
def test_each_kind_needs_at_least_its_whole_struct(kind, size):
    """A buffer of exactly the struct's words (trajectory.h; the polygon's without its points)
    gets past the size check; one word fewer, or none, is refused as BAD_LAYOUT with index -1 and
    the word count as value."""
    buf = _all_kinds()[kind]
    if kind != "polygon":      # a polygon's points come after its struct: checked above
        assert buf.size == size and _sample(buf, 0.1, words=size)[0] == F.OK
    for words in (size - 1, 0):
        code, refusal, _ = _sample(buf, 0.1, words=words)
        assert (code, refusal.index, refusal.value) == (F.BAD_LAYOUT, -1, float(words)), words
