"""5R closed-form kinematics (seed 002) in the contract's world convention."""
import math

import numpy as np
import pytest

from plant import get_preset
from plant.fivebar import (KinematicsError, build_mechanism, direct_kinematics, elbows, inverse_kinematics,
                           jacobians, joint_rates, singularity, thesis_coordinates, workspace_map,
                           NEAR_SINGULAR_MARGIN)
from plant.parallel import mechanism_state

PRESETS = ("thesis_sim", "bench")


def workspace_points(params, n=40, seed=1):
    """Random points of the upper workspace away from singularities."""
    rng = np.random.default_rng(seed)
    points = []
    while len(points) < n:
        x, y = rng.uniform(-0.12, 0.12), rng.uniform(0.06, 0.26)
        try:
            if singularity(params, x, y).margin > 0.2:
                points.append((x, y))
        except KinematicsError:
            pass
    return points


def test_contract_angles():
    """The brief ../shared/spec/SYSTEM.md section 2: elbows outward, angles CCW from +x."""
    p = get_preset("thesis_sim")
    q = inverse_kinematics(p, 0.0, 0.17)
    assert math.degrees(q[0]) == pytest.approx(49.6, abs=0.05)
    assert math.degrees(q[2]) == pytest.approx(130.4, abs=0.05)
    q = inverse_kinematics(p, 0.07, 0.17)
    assert math.degrees(q[0]) == pytest.approx(24.36, abs=0.005)
    assert math.degrees(q[2]) == pytest.approx(99.97, abs=0.005)


@pytest.mark.parametrize("preset", PRESETS)
def test_ik_fk_round_trip(preset):
    """Catches inverse and direct kinematics that disagree, or an inverse that puts a distal link off the tip."""
    p = get_preset(preset)
    for x, y in workspace_points(p):
        q = inverse_kinematics(p, x, y)
        np.testing.assert_allclose(direct_kinematics(p, q[0], q[2]), [x, y], atol=1e-13)
        # Each distal link ends at the end effector.
        elbow1 = np.array([p.l0, 0]) + p.chain1.l1 * np.array([math.cos(q[0]), math.sin(q[0])])
        tip1 = elbow1 + p.chain1.l2 * np.array([math.cos(q[1]), math.sin(q[1])])
        np.testing.assert_allclose(tip1, [x, y], atol=1e-14)


@pytest.mark.parametrize("preset", PRESETS)
def test_elbows_are_one_proximal_link_from_their_bases_and_one_distal_link_from_the_tip(preset):
    """Each elbow A_k = B_k + l_k1 (cos q_k, sin q_k), B_1 = (l0, 0), B_2 = (-l0, 0) (the
    contract's bases, written here), and the tip is one distal link l_k2 from it along the
    inverse kinematics' phi_k2.  Catches an elbow without its base (the offset of +-l0 dropped),
    the chains' links or angles swapped, and sin/cos exchanged."""
    p = get_preset(preset)
    for x, y in workspace_points(p, n=10):
        phi11, phi12, phi21, phi22 = inverse_kinematics(p, x, y)
        a = elbows(p, phi11, phi21)
        assert a.shape == (2, 2)
        for k, (chain, base, q, phi2) in enumerate(((p.chain1, (p.l0, 0.0), phi11, phi12),
                                                     (p.chain2, (-p.l0, 0.0), phi21, phi22))):
            expected = (base[0] + chain.l1 * math.cos(q), base[1] + chain.l1 * math.sin(q))
            np.testing.assert_allclose(a[k], expected, rtol=0, atol=1e-15)
            tip = a[k] + chain.l2 * np.array([math.cos(phi2), math.sin(phi2)])
            np.testing.assert_allclose(tip, (x, y), rtol=0, atol=1e-12)


@pytest.mark.parametrize("preset", PRESETS)
def test_thesis_coordinates_close_the_loop(preset):
    """Catches thesis coordinates (7.12) of a pose that leave the loop-closure residual open."""
    p = get_preset(preset)
    mech = build_mechanism(p)
    for x, y in workspace_points(p, 10):
        st = mechanism_state(mech, thesis_coordinates(p, x, y), np.zeros(7))
        assert np.max(np.abs(st.residual)) < 1e-15


@pytest.mark.parametrize("preset", PRESETS)
def test_jacobians_match_finite_differences(preset):
    """Catches a wrong sign, index or term in J_X, J_Theta or the joint rates (central differences of the IK)."""
    p = get_preset(preset)
    eps = 1e-7
    for x, y in workspace_points(p, 10):
        q = inverse_kinematics(p, x, y)
        # J_X dX + J_Theta dTheta = 0: dTheta/dX by differencing the inverse kinematics.
        dtheta_dx = np.column_stack([
            (inverse_kinematics(p, x + eps * e[0], y + eps * e[1])[[0, 2]]
             - inverse_kinematics(p, x - eps * e[0], y - eps * e[1])[[0, 2]]) / (2 * eps)
            for e in np.eye(2)
        ])
        JX, JT = jacobians(p, x, y, q[0], q[2])
        np.testing.assert_allclose(-np.linalg.solve(JT, JX), dtheta_dx, rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(joint_rates(p, x, y, q[0], q[2], 0.1, -0.2), dtheta_dx @ [0.1, -0.2], atol=1e-6)


def test_singularity_measures_vanish_at_singular_poses():
    """Catches serial or parallel singularity measures that do not vanish at a stretched chain or flat links."""
    p = get_preset("thesis_sim")
    # Chain 1 stretched: the tip at distance l1 + l2 from its base.
    reach = (p.chain1.l1 + p.chain1.l2) * (1 - 1e-10)
    s = singularity(p, p.l0 + reach * math.cos(1.9), reach * math.sin(1.9))
    assert abs(s.serial1) < 1e-4
    # Parallel singularity: both distal links horizontal, the tip between the elbows
    # at (0, l1 sin q1) with l0 + l1 cos q1 = l2.
    q1 = math.acos((p.chain1.l2 - p.l0) / p.chain1.l1)
    s = singularity(p, 0.0, p.chain1.l1 * math.sin(q1))
    assert abs(s.parallel) < 1e-9
    assert singularity(p, 0.0, 0.17).margin > 0.5


def test_workspace_map_has_a_near_singular_band():
    """Catches a workspace map whose status disagrees with its margin or misses a region (inside, near, outside)."""
    p = get_preset("thesis_sim")
    ws = workspace_map(p, step=0.01)
    counts = np.bincount(ws.status.ravel(), minlength=3)
    assert counts[ws.INSIDE] > 100 and counts[ws.NEAR_SINGULAR] > 5 and counts[ws.OUTSIDE] > 100
    inside = ~np.isnan(ws.margin)
    assert np.all((ws.margin[inside] < NEAR_SINGULAR_MARGIN) == (ws.status[inside] == ws.NEAR_SINGULAR))


def test_unreachable_point_is_named():
    """Catches an inverse kinematics that returns NaN or a wrong pose for an unreachable point instead of naming it."""
    with pytest.raises(KinematicsError, match=r"x=0\.5.*outside the workspace"):
        inverse_kinematics(get_preset("bench"), 0.5, 0.1)


def test_no_assembly_when_the_elbows_are_farther_apart_than_the_distal_links_reach():
    """q1 = 0, q2 = pi: elbows at (+-(l0 + l1), 0), 0.34 m apart; two distal links of 0.16 m
    cannot close the loop (002 eq. 7-11)."""
    with pytest.raises(KinematicsError, match="no assembly"):
        direct_kinematics(get_preset("bench"), 0.0, math.pi)


def test_workspace_map_covers_the_reach():
    """The grid spans the documented square [-l0 - reach, l0 + reach] x [-reach, reach]; the
    highest reachable point of the equal-chain thesis_sim is (0, sqrt((l1 + l2)^2 - l0^2))."""
    p, step = get_preset("thesis_sim"), 0.007          # not a divisor of the extent: the end is not a grid point
    ws = workspace_map(p, step=step)
    reach = p.chain1.l1 + p.chain1.l2
    assert ws.x[0] == -p.l0 - reach and abs(ws.x[-1] - (p.l0 + reach)) < step / 2
    assert ws.y[0] == -reach and abs(ws.y[-1] - reach) < step / 2
    top = max(ws.y[iy] for iy, ix in np.argwhere(ws.status != ws.OUTSIDE))
    assert math.sqrt(reach ** 2 - p.l0 ** 2) - step < top <= math.sqrt(reach ** 2 - p.l0 ** 2)


def test_parallel_measure_changes_sign_where_the_general_algorithms_determinant_does():
    """Along x = 0 through the parallel singularity (thesis_sim), the C kinematics' parallel
    measure (plant.fivebar.singularity) changes sign at the same height as det of the general
    algorithm's actuated rows of C (5.56): dtheta_actuated = C_a dX, det C_a = -det J_X / det J_Theta.
    A margin built from the wrong link angles would cross elsewhere or not at all."""
    p = get_preset("thesis_sim")
    mech = build_mechanism(p)
    ys = np.linspace(0.05, 0.20, 301)
    measure, det_general = [], []
    for y in ys:
        measure.append(singularity(p, 0.0, y).parallel)
        C = mechanism_state(mech, thesis_coordinates(p, 0.0, y), np.zeros(7)).C
        det_general.append(np.linalg.det(C[[3, 5]]))
    cross_measure = np.flatnonzero(np.diff(np.sign(measure)))
    cross_general = np.flatnonzero(np.diff(np.sign(det_general)))
    assert cross_measure.size == 1
    np.testing.assert_array_equal(cross_measure, cross_general)
    q1 = math.acos((p.chain1.l2 - p.l0) / p.chain1.l1)   # the analytic crossing (see above)
    assert ys[cross_measure[0]] <= p.chain1.l1 * math.sin(q1) <= ys[cross_measure[0] + 1]


def test_chain_2s_base_frame_is_the_half_turn_about_y_of_7_4():
    """E_2 of (7.4) (plant.fivebar.MIRROR in the mechanism's E, (7.10)) is a rotation, the half
    turn about y: x -> -x, y -> y, z -> -z; chain 1's is the identity.  A spec's rotation must be
    orthonormal with det +1 too (plant/spec.py).  Catches any entry of E_2 changed (its z row
    never meets a planar motion, so no dynamics shows it)."""
    E = build_mechanism(get_preset("bench")).E
    half_turn = np.array([[math.cos(math.pi), 0.0, math.sin(math.pi)], [0.0, 1.0, 0.0],
                          [-math.sin(math.pi), 0.0, math.cos(math.pi)]])
    assert np.array_equal(E[:3, :3], np.eye(3)) and not E[:3, 3:].any() and not E[3:, :3].any()
    np.testing.assert_allclose(E[3:, 3:], half_turn, rtol=0, atol=1e-15)
    assert np.allclose(E[3:, 3:] @ E[3:, 3:].T, np.eye(3), atol=1e-15) and np.linalg.det(E[3:, 3:]) == 1.0
