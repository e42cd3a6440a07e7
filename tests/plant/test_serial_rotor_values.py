"""plant/serial.py's rotor terms (4.139) at exact values: a rotor of exactly 1 kg m2 counts
like any other, one of 0 adds nothing.  On the planar RR every axis is z, so a rotor on joint
i with gear r adds J (dw/ddq)^T (dw/ddq) with dw/ddq the rotor's spin per joint rate:
joint 1: (r, 0); joint 2: (1, r), the rotor riding on link 1."""
from __future__ import annotations

import numpy as np
import pytest

from plant import spec as plant_spec
from plant.serial import SerialChain, chain_dynamics

RR = plant_spec.load("rr").chains[0].chain
Q, DQ = np.array([0.4, -0.9]), np.array([0.0, 0.0])


def _M(rotor, gear):
    chain = SerialChain(RR.joints, RR.links, rotor_inertia=rotor, gear_ratio=gear)
    return chain_dynamics(chain, Q, DQ, np.zeros(3)).M


@pytest.mark.parametrize("J", [1.0, 0.25])
def test_a_rotor_adds_its_inertia_through_its_spin_per_joint_rate(J):
    bare = _M((0.0, 0.0), (1.0, 1.0))
    np.testing.assert_allclose(_M((J, 0.0), (3.0, 1.0)) - bare, J * np.array([[9.0, 0.0], [0.0, 0.0]]),
                               rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(_M((0.0, J), (1.0, 3.0)) - bare, J * np.array([[1.0, 3.0], [3.0, 9.0]]),
                               rtol=1e-13, atol=1e-15)


def test_a_rotor_of_zero_inertia_adds_nothing_whatever_its_gear():
    np.testing.assert_array_equal(_M((0.0, 0.0), (5.0, -7.0)), _M((0.0, 0.0), (1.0, 1.0)))


def test_a_chain_s_tuples_of_other_lengths_are_refused_naming_the_counts():
    """One link, one rotor and one gear per joint; the empty defaults mean none and 1."""
    with pytest.raises(ValueError, match=r"^2 joints but 1 links$"):
        SerialChain(RR.joints, RR.links[:1])
    for rotor, gear in [((0.0,), ()), ((), (1.0, 1.0, 1.0))]:
        with pytest.raises(ValueError, match=r"^rotor_inertia and gear_ratio need one entry per joint$"):
            SerialChain(RR.joints, RR.links, rotor_inertia=rotor, gear_ratio=gear)
    chain = SerialChain(RR.joints, RR.links)
    assert (chain.rotor_inertia, chain.gear_ratio, chain.dof) == ((0.0, 0.0), (1.0, 1.0), 2)
