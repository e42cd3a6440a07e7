"""The position law kernel's reach refusals (kernels/src/law.c, pc_law_prepare and
pc_law_exact_pose) for each chain separately: a point one chain reaches and the other does not,
beyond its outer circle or inside its inner one, is refused naming that chain (the kernel's
index: 0 chain 1, based at (+l0, 0); 1 chain 2, at (-l0, 0)) with that chain's distance from its
base, computed here with math.hypot.  The stepping tests only ever met references out of both
chains' reach or of chain 1's, so chain 2's refusal lines never ran."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from controller import law
from controller.position import PositionController
from controller.strategies import get_strategy
from plant import fivebar, get_preset

BENCH = get_preset("bench")
L0 = BENCH.l0
#: Each chain's reach: the annulus between |l1 - l2| and l1 + l2 about its base.
INNER, OUTER = abs(BENCH.chain1.l1 - BENCH.chain1.l2), BENCH.chain1.l1 + BENCH.chain1.l2
#: (x, y), the chain (0: chain 1, 1: chain 2) that cannot reach it.
POINTS = [((0.25, 0.15), 1), ((-0.25, 0.15), 0),          # beyond the outer circle of one chain
          ((-0.02, 0.005), 1), ((0.02, 0.005), 0)]         # inside the inner circle of one chain


def base(chain):
    return (L0, 0.0) if chain == 0 else (-L0, 0.0)


def distance(point, chain):
    bx, by = base(chain)
    return math.hypot(point[0] - bx, point[1] - by)


def test_the_points_are_out_of_one_chains_reach_only():
    """The cases are what they say: each point in one chain's annulus and out of the other's."""
    assert BENCH.chain1.l1 == BENCH.chain2.l1 and BENCH.chain1.l2 == BENCH.chain2.l2
    for point, out in POINTS:
        assert INNER <= distance(point, 1 - out) <= OUTER
        assert not INNER <= distance(point, out) <= OUTER


@pytest.mark.parametrize("strategy", ["PDq", "PDx"])
@pytest.mark.parametrize("point, out", POINTS)
def test_a_reference_one_chain_cannot_reach_is_refused_naming_that_chain_and_its_distance(strategy, point, out):
    """REF_OUT from the sample, the kernel's index the chain, its value and the record's the
    chain's distance from its base; in task space (PDx) too, whose law checks a reference's
    reach only when it is not clearly inside."""
    ctrl = PositionController(BENCH, get_strategy(strategy), model="exact")
    ang = fivebar.inverse_kinematics(BENCH, 0.01, 0.15)
    with pytest.raises(kernels.Refused) as caught:
        ctrl.step_with_errors(0.5, ang[0], ang[2], 0.0, 0.0, 0.0, 0.0, *point, 0.1, -0.2, 0.0, 0.0)
    assert caught.value.reason == "REF_OUT"
    refusal = ctrl._binding().refusal
    assert (refusal.code, refusal.index) == (law.REF_OUT, out)
    assert refusal.value == pytest.approx(distance(point, out), rel=1e-14)
    assert caught.value.record()["value"] == refusal.value


@pytest.mark.parametrize("point, out", POINTS)
def test_the_exact_pose_of_a_point_one_chain_cannot_reach_is_refused_with_that_chains_distance(point, out):
    """pc_law_exact_pose (the table's fallback to the exact model) on a measured pose out of one
    chain's reach: EXACT_OUT with that chain's distance from its base; q and dq untouched."""
    ctrl = PositionController(BENCH, get_strategy("PDq"), model="exact")
    b = ctrl._binding()
    ctrl._scratch[law.POSE] = point
    ctrl._scratch[law.Q] = 7.0
    assert b.exact_pose() == law.EXACT_OUT
    assert (b.refusal.code, b.refusal.index) == (law.EXACT_OUT, 0)
    assert b.refusal.value == pytest.approx(distance(point, out), rel=1e-14)
    assert (ctrl._scratch[law.Q] == 7.0).all()


def test_the_exact_pose_of_a_reachable_point_is_the_thesis_coordinates():
    """A reachable measured pose: q is plant.fivebar.thesis_coordinates (7.12) of it."""
    ctrl = PositionController(BENCH, get_strategy("PDq"), model="exact")
    b = ctrl._binding()
    ctrl._scratch[law.POSE] = (0.03, 0.17)
    assert b.exact_pose() == law.OK
    np.testing.assert_allclose(ctrl._scratch[law.Q], fivebar.thesis_coordinates(BENCH, 0.03, 0.17), rtol=0,
                               atol=1e-13)
