"""The bench triangle (7.24-7.27) with other side times and cycle counts than the thesis' 0.75 s
and 2: the same path in scaled time, and as many rounds as asked."""
import numpy as np
import pytest

from controller.trajectories import get_trajectory


@pytest.mark.parametrize("side_time", [0.3, 1.25])
def test_a_triangle_with_another_side_time_is_the_thesis_triangle_in_scaled_time(side_time):
    """triangle(side_time=s) at t is triangle() at t 0.75/s, with velocity x 0.75/s and
    acceleration x (0.75/s)^2.  Catches a polynomial (7.27) evaluated at t / 0.75 instead of
    t / s, or derivatives not divided by s (and s^2)."""
    k = 0.75 / side_time
    scaled, thesis = get_trajectory("triangle", side_time=side_time), get_trajectory("triangle")
    assert scaled.duration == pytest.approx(6 * side_time)
    for t in np.linspace(0.0, 6 * side_time, 61):
        a, b = scaled(t), thesis(k * t)
        np.testing.assert_allclose([a.x, a.y], [b.x, b.y], rtol=0, atol=1e-14)
        np.testing.assert_allclose([a.dx, a.dy], [k * b.dx, k * b.dy], rtol=0, atol=1e-12)
        np.testing.assert_allclose([a.ddx, a.ddy], [k ** 2 * b.ddx, k ** 2 * b.ddy], rtol=0, atol=1e-10)


def test_more_cycles_repeat_the_rounds_and_then_hold():
    """Catches a cycle count that is not the number of rounds (the path of round 3 is round 1's,
    3 s later than round 2's, then the hold at x_1)."""
    three, two = get_trajectory("triangle", cycles=3), get_trajectory("triangle", cycles=2)
    assert three.duration == pytest.approx(6.75)
    for t in np.linspace(0.0, 2.25, 23):
        assert three(t + 4.5) == pytest.approx(two(t), abs=1e-13)
        assert three(t + 2.25) == pytest.approx(three(t), abs=1e-13)
    assert three(6.75) == three(9.0) == two(4.5)
    assert three(5.0) != two(5.0)
