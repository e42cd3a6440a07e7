"""PlantSimulator's construction checks at their boundaries (plant/simulator.py), accepted on the
allowed side and refused word for word on the other, and the coarsest encoders read by the rule
its docstring states (q + offset to the nearest whole count), worked out here."""
from __future__ import annotations

import math

import pytest

from plant import PlantSimulator, fivebar, get_preset

START = (-0.002, 0.108)      # the bench circle's start: q1 = 0.559, q2 = 2.626 rad
Y_SINGULAR = 0.04784767528116976    # bench: the parallel singularity below x = -0.002


def _reading(q, counts):
    count = 2.0 * math.pi / counts
    return count * math.floor(q / count + 0.5)


@pytest.mark.parametrize("counts", [1, 2, 3])
def test_the_coarsest_encoders_are_accepted_and_read_whole_counts(counts):
    """One, two and three counts per revolution (1 is the smallest positive integer) are
    accepted; the readings before and after a compiled step are q rounded to whole counts of
    2 pi / counts (q2 = 2.63 rad reads 0, pi and 2 pi / 3).  Catches the check refusing 1
    (``> 1``, ``>= 2``) and a count other than 2 pi / counts."""
    sim = PlantSimulator(get_preset("bench"), *START, encoder_counts=counts)
    assert sim.encoder_counts == counts and sim.count == 2.0 * math.pi / counts
    for _ in range(2):
        out = sim.outputs()
        for k in (1, 2):
            assert out[f"q{k}_enc"] == pytest.approx(_reading(out[f"q{k}"], counts), abs=1e-15)
        sim.step(0.01, -0.01, 2e-3)
    assert sim.outputs()["q2_enc"] == pytest.approx((0.0, math.pi, 2.0 * math.pi / 3.0)[counts - 1], abs=1e-15)


@pytest.mark.parametrize("counts", [0, -1, 2.0, "1024", None])
def test_encoder_counts_that_are_not_a_positive_integer_are_refused_word_for_word(counts):
    """Catches the check's ``isinstance`` or ``> 0`` dropped or loosened (0 accepted, a float
    accepted), and a message that does not name the parameter and its value."""
    with pytest.raises(ValueError) as info:
        PlantSimulator(get_preset("bench"), *START, encoder_counts=counts)
    assert str(info.value) == f"encoder_counts must be a positive integer, got {counts!r}"


def test_a_start_out_of_reach_is_refused_with_the_point_and_the_distance():
    """Catches the start's kinematics error passed on without the start point, or another
    point named."""
    with pytest.raises(ValueError) as info:
        PlantSimulator(get_preset("bench"), 5.0, 0.108)
    assert str(info.value) == ("start point x0=5.0, y0=0.108: point (x=5, y=0.108) is outside the workspace: "
                               "point out of reach of a chain (distance 4.95118 m)")


def test_a_start_within_the_singular_stop_is_refused_and_one_just_outside_accepted():
    """The margin of 1e-3 (SINGULAR_STOP) decides: 5e-5 m from the parallel singularity the
    margin is 6.2e-4, refused with it; 5e-4 m away it is above 1e-3, accepted.  Catches the
    check dropped, its comparison reversed, and a message without the point or margin."""
    params = get_preset("bench")
    near, clear = Y_SINGULAR + 5e-5, Y_SINGULAR + 5e-4
    assert fivebar.singularity(params, -0.002, near).margin < 1e-3 < fivebar.singularity(params, -0.002, clear).margin
    with pytest.raises(ValueError) as info:
        PlantSimulator(params, -0.002, near)
    assert str(info.value) == f"start point x0=-0.002, y0={near!r} is singular (margin 0.000623)"
    assert PlantSimulator(params, -0.002, clear).outputs()["y"] == pytest.approx(clear, abs=1e-15)
