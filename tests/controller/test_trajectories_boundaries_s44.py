"""controller/trajectories.py ``from_parameters`` at the edges of its refusals (issue 31,
training sweep s44: compare mutants at trajectories.py:387, :389 and :397).

cycles: at least 1 (not the preset -1), and for the triangle at most the kernel's MAX_CYCLES;
side_time: > 0.  Each edge is taken exactly (the trajectory has that value) and the next value
past it is refused naming the parameter, its value and the bound.
"""
from __future__ import annotations

import pytest

from controller import trajectories
from controller.trajectories import from_parameters

MAX = trajectories._fast.MAX_CYCLES


@pytest.mark.parametrize("cycles", [1, MAX])
def test_one_cycle_and_the_triangles_most_are_taken(cycles):
    assert from_parameters("triangle", cycles).cycles == cycles


def test_one_cycle_of_the_circle_is_taken_and_lasts_half_of_two():
    one, two = from_parameters("circle", 1), from_parameters("circle", 2)
    assert one.duration > 0.0 and two.duration == 2 * one.duration


@pytest.mark.parametrize("kind", ["circle", "triangle"])
def test_zero_cycles_are_refused_naming_the_least(kind):
    with pytest.raises(ValueError, match=r"^parameter cycles = 0 must be >= 1 \(or -1 for the default\)$"):
        from_parameters(kind, 0)


def test_one_round_more_than_the_most_is_refused_for_the_triangle():
    with pytest.raises(ValueError, match=rf"^parameter cycles = {MAX + 1} must be <= {MAX} \(rounds of the triangle\)$"):
        from_parameters("triangle", MAX + 1)


def test_the_least_positive_side_time_is_taken_and_zero_refused():
    assert from_parameters("triangle", side_time=5e-324).side_time == 5e-324
    with pytest.raises(ValueError, match=r"^parameter side_time = 0.0 s must be > 0$"):
        from_parameters("triangle", side_time=0.0)
