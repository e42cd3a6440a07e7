"""The controller's kinematics (the C kernel kinematics5r.c) against plant.fivebar and the general
algorithm's C, c."""
import numpy as np
import pytest

from controller.kinematics import Kinematics
from plant import fivebar, get_preset
from plant.parallel import inverse_dynamics_terms, mechanism_state

POINTS = [(0.0, 0.17), (0.07, 0.17), (-0.04, 0.12), (0.03, 0.25)]


@pytest.mark.parametrize("preset", ["bench", "thesis_sim"])
@pytest.mark.parametrize("x, y", POINTS)
def test_kinematics_match_the_plant(preset, x, y):
    """Catches controller kinematics (C) that differ from the plant's inverse, direct kinematics or margin."""
    params = get_preset(preset)
    kin, mech = Kinematics(params), fivebar.build_mechanism(params)
    ang = fivebar.inverse_kinematics(params, x, y)
    assert np.allclose(kin.inverse(x, y), ang, atol=1e-14)
    assert np.allclose(kin.forward(ang[0], ang[2]), (x, y), atol=1e-14)
    assert kin.margin(x, y) == pytest.approx(fivebar.singularity(params, x, y).margin, abs=1e-14)
    q7 = fivebar.thesis_coordinates(params, x, y)
    C = mechanism_state(mech, q7, np.zeros(7)).C
    dxy = np.array([0.3, -0.2])
    dq7 = C @ dxy
    q_thesis, dq_thesis = kin.thesis_state(x, y, *dxy)
    assert np.allclose(q_thesis, q7, atol=1e-14) and np.allclose(dq_thesis, dq7, atol=1e-13)
    # Joint accelerations at ddx# = 0 are the constraint bias c (5.69): task_state must give ddx = 0.
    c = inverse_dynamics_terms(mech, q7, dq7).c
    dq1, dq2 = fivebar.world_rates(dq7)
    ddq1, ddq2 = fivebar.world_rates(c)
    state = kin.task_state(ang[0], ang[2], dq1, dq2, ddq1, ddq2)
    assert np.allclose(state[2:4], dxy, atol=1e-13)
    assert np.allclose(state[4:6], 0.0, atol=1e-12)
    # joint_reference inverts task_state.
    ddx = (1.5, -0.7)
    ref = kin.joint_reference(x, y, *dxy, *ddx)
    back = kin.task_state(*ref)
    assert np.allclose(back[:6], (x, y, *dxy, *ddx), atol=1e-12)


def _quarters():
    """The bench with every length 1/4 m: q1 = q2 = 0 puts the elbows at (1/2, 0) and (0, 0)
    and the tip at (1/4, 0) with both distal links on the x axis (det J_X = 0 exactly), where
    chain 1 is folded (its tip on its base) and chain 2 stretched."""
    from dataclasses import replace

    bench = get_preset("bench")
    return Kinematics(replace(bench, l0=0.25, chain1=replace(bench.chain1, l1=0.25, l2=0.25),
                              chain2=replace(bench.chain2, l1=0.25, l2=0.25)))


def test_each_refusal_names_its_pose_word_for_word():
    """Every refusal of the controller's kinematics, read back whole with values that show the
    six significant digits: out of reach (inverse), no assembly (forward, task_state), a
    parallel singularity (task_state at the flat pose) and a stretched or folded chain
    (joint_reference), each a KinematicsError (a ValueError); a pose off the singularity
    is accepted.  Catches a refusal raised without its text, naming the other
    angle or another quantity, or the singularity taken for a missing assembly."""
    kin = _quarters()
    assert kin.forward(0.0, 0.0) == (0.25, 0.0)
    cases = [
        (lambda: kin.task_state(0.0, 0.0, 0.125, -0.5, 2.0, 3.0),
         "q1=0, q2=0 rad is a parallel singularity (det J_X = 0)"),
        (lambda: kin.task_state(0.123456789, 3.0, 0.0, 0.0, 0.0, 0.0),
         f"no assembly for q1=0.123457, q2=3 rad (elbow distance {_elbow_distance(kin, 0.123456789, 3.0):.6g} m)"),
        (lambda: kin.forward(0.123456789, 3.0),
         f"no assembly for q1=0.123457, q2=3 rad (elbow distance {_elbow_distance(kin, 0.123456789, 3.0):.6g} m)"),
        (lambda: kin.inverse(2.0, 0.1), "point out of reach of a chain (distance 1.75285 m)"),
        (lambda: kin.joint_reference(0.25, 0.0, 0.1, 0.0, 0.0, 0.0),
         "(x, y) = (0.25, 0) m: a chain is stretched or folded (J_Theta singular)"),
    ]
    for call, words in cases:
        with pytest.raises(fivebar.KinematicsError) as caught:
            call()
        assert str(caught.value) == words
        assert isinstance(caught.value, ValueError)
    x, y, *_ = kin.task_state(0.5, 0.0, 0.125, -0.5, 2.0, 3.0)           # chain 1 turned off the flat pose
    assert (x, y) == pytest.approx(kin.forward(0.5, 0.0), abs=1e-15) and y > 0.0


def _elbow_distance(kin, q1, q2):
    """The elbows' distance at (q1, q2), from the geometry written here: the bases at (+-l0, 0),
    elbow 1 at (l0 + l11 cos q1, l11 sin q1), elbow 2 at (-l0 + l21 cos q2, l21 sin q2)."""
    import math

    e1 = (kin.l0 + kin.l11 * math.cos(q1), kin.l11 * math.sin(q1))
    e2 = (-kin.l0 + kin.l21 * math.cos(q2), kin.l21 * math.sin(q2))
    return math.hypot(e1[0] - e2[0], e1[1] - e2[1])


def _one_chain_folded(chain: int):
    """The bench with l0 = 1/4 m, the chain ``chain`` (1 or 2) of two 1/4 m links and the other of
    two 0.3 m links: the tip at that chain's base, (l0, 0) for chain 1 or (-l0, 0) for chain 2,
    folds it (its J_Theta entry (x -+ l0) sin q - y cos q is 0 exactly) while the other chain,
    its base 0.5 m away, is bent (sin q != 0)."""
    from dataclasses import replace

    bench = get_preset("bench")
    folded, bent = replace(bench.chain1, l1=0.25, l2=0.25), replace(bench.chain1, l1=0.3, l2=0.3)
    chains = (folded, bent) if chain == 1 else (bent, folded)
    return Kinematics(replace(bench, l0=0.25, chain1=chains[0], chain2=chains[1]))


@pytest.mark.parametrize("chain, x", [(1, 0.25), (2, -0.25)])
def test_joint_reference_refuses_a_pose_where_one_chain_alone_is_folded(chain, x):
    """One chain folded (J_Theta's entry of that chain 0, the other's not) is as singular as both:
    dq of that joint would be a division by zero.  Catches a singularity check of the one
    entry that misses its zero (the bend test of the other chain alone refusing)."""
    kin = _one_chain_folded(chain)
    angles = kin.inverse(x, 0.0)
    *_, t1, t2 = kin.jacobians(x, 0.0, angles[0], angles[2])
    assert (t1, t2)[chain - 1] == 0.0 and (t1, t2)[2 - chain] != 0.0
    with pytest.raises(fivebar.KinematicsError, match="a chain is stretched or folded"):
        kin.joint_reference(x, 0.0, 0.1, 0.05, 0.0, 0.0)
    # off the fold, a finite reference
    assert np.isfinite(kin.joint_reference(x, 0.01, 0.1, 0.05, 0.0, 0.0)).all()
