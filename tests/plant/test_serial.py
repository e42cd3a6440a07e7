"""The recursive serial-chain algorithm (thesis 4.1-4.87, 4.139-4.140) against
finite differences and the Lagrange equations, on a 3-D chain with revolute
and prismatic joints and a rotor."""
import numpy as np
import pytest

from plant.serial import DHJoint, RigidLink, SerialChain, chain_dynamics, chain_kinematics, with_point_mass

EPS = 1e-6


def spatial_chain():
    """An RPRR chain with twisted axes, offsets and full inertia tensors."""
    rng = np.random.default_rng(7)

    def inertia():
        a = rng.normal(size=(3, 3)) * 0.01
        return a @ a.T + 1e-3 * np.eye(3)

    joints = (
        DHJoint("R", a=0.1, alpha=np.pi / 2, d=0.05, theta=0.2),
        DHJoint("P", a=0.05, alpha=-0.4, d=0.1, theta=0.3),
        DHJoint("R", a=0.2, alpha=0.7, d=-0.03),
        DHJoint("R", a=0.15, alpha=0.0, d=0.02),
    )
    links = tuple(RigidLink(m, rng.normal(size=3) * 0.05, inertia()) for m in (0.5, 0.3, 0.4, 0.2))
    return SerialChain(joints, links, rotor_inertia=(2e-3, 0.0, 1e-3, 5e-4), gear_ratio=(3.0, 1.0, 2.0, 1.0))


CHAIN = spatial_chain()
STATES = [np.random.default_rng(s).normal(size=(2, 4)) for s in range(3)]


def _com_positions(q):
    return chain_kinematics(CHAIN, q, np.zeros(4)).com


@pytest.mark.parametrize("q, dq", STATES)
def test_jacobians_match_finite_differences(q, dq):
    """Catches a wrong column, sign or frame in the linear and angular Jacobians of the serial chain."""
    kin = chain_kinematics(CHAIN, q, dq)
    for j in range(4):
        step = np.zeros(4)
        step[j] = EPS
        plus, minus = chain_kinematics(CHAIN, q + step, dq), chain_kinematics(CHAIN, q - step, dq)
        np.testing.assert_allclose(kin.Jv_tip[:, j], (plus.tip - minus.tip) / (2 * EPS), atol=1e-8)
        np.testing.assert_allclose(kin.Jv_com[:, :, j], (plus.com - minus.com) / (2 * EPS), atol=1e-8)
        # Angular Jacobian: d R / dq_j R^T = skew(J_w column).
        dR = (plus.frames[1:, :3, :3] - minus.frames[1:, :3, :3]) / (2 * EPS)
        for i in range(4):
            W = dR[i] @ kin.frames[i + 1, :3, :3].T
            np.testing.assert_allclose([W[2, 1], W[0, 2], W[1, 0]], kin.Jw_link[i][:, j], atol=1e-8)


@pytest.mark.parametrize("q, dq", STATES)
def test_velocity_quadratic_terms_are_dJ_dq(q, dq):
    """a_bias = (d/dt J) dq along the motion (4.56, 4.62, 4.75, 4.81)."""
    kin = chain_kinematics(CHAIN, q, dq)
    plus, minus = chain_kinematics(CHAIN, q + EPS * dq, dq), chain_kinematics(CHAIN, q - EPS * dq, dq)
    np.testing.assert_allclose(kin.a_tip_bias, (plus.Jv_tip - minus.Jv_tip) @ dq / (2 * EPS), atol=1e-7)
    np.testing.assert_allclose(kin.alpha_tip_bias, (plus.Jw_tip - minus.Jw_tip) @ dq / (2 * EPS), atol=1e-7)
    for i in range(4):
        np.testing.assert_allclose(kin.a_com_bias[i], (plus.Jv_com[i] - minus.Jv_com[i]) @ dq / (2 * EPS), atol=1e-7)
        np.testing.assert_allclose(kin.alpha_link_bias[i], (plus.Jw_link[i] - minus.Jw_link[i]) @ dq / (2 * EPS),
                                   atol=1e-7)


def _kinetic_energy_from_motion(q, dq):
    """T from finite-difference velocities of the bodies, independent of the Jacobians."""
    plus, minus = chain_kinematics(CHAIN, q + EPS * dq, dq), chain_kinematics(CHAIN, q - EPS * dq, dq)
    kin = chain_kinematics(CHAIN, q, dq)
    T = 0.0
    for i, link in enumerate(CHAIN.links):
        v = (plus.com[i] - minus.com[i]) / (2 * EPS)
        R = kin.frames[i + 1, :3, :3]
        W = (plus.frames[i + 1, :3, :3] - minus.frames[i + 1, :3, :3]) / (2 * EPS) @ R.T
        w = np.array([W[2, 1], W[0, 2], W[1, 0]])
        T += 0.5 * link.mass * v @ v + 0.5 * w @ (R @ np.array(link.inertia) @ R.T) @ w
    for i, Jr in enumerate(CHAIN.rotor_inertia):
        # Rotor i spins about k_{i-1} at r_i dq_i relative to link i-1 (4.124-4.127).
        axis = kin.frames[i, :3, 2]
        w_carrier = np.zeros(3) if i == 0 else kin.Jw_link[i - 1] @ dq
        w = w_carrier + CHAIN.gear_ratio[i] * dq[i] * axis
        T += 0.5 * Jr * (w @ axis) ** 2
    return T


@pytest.mark.parametrize("q, dq", STATES)
def test_mass_matrix_gives_the_kinetic_energy(q, dq):
    """Catches a mass matrix that is not symmetric positive definite or not the chain's kinetic energy."""
    M = chain_dynamics(CHAIN, q, dq, np.zeros(3)).M
    np.testing.assert_allclose(M, M.T, atol=1e-14)
    assert np.all(np.linalg.eigvalsh(M) > 0)
    np.testing.assert_allclose(0.5 * dq @ M @ dq, _kinetic_energy_from_motion(q, dq), rtol=1e-8)


@pytest.mark.parametrize("q, dq", STATES)
def test_velocity_terms_are_the_christoffel_terms_of_M(q, dq):
    """v_i = sum_jk (dM_ij/dq_k - 1/2 dM_jk/dq_i) dq_j dq_k (Lagrange)."""
    dM = np.empty((4, 4, 4))
    for k in range(4):
        step = np.zeros(4)
        step[k] = EPS
        dM[:, :, k] = (chain_dynamics(CHAIN, q + step, dq, np.zeros(3)).M
                       - chain_dynamics(CHAIN, q - step, dq, np.zeros(3)).M) / (2 * EPS)
    v_lagrange = np.einsum("ijk,j,k->i", dM, dq, dq) - 0.5 * np.einsum("jki,j,k->i", dM, dq, dq)
    v = chain_dynamics(CHAIN, q, dq, np.zeros(3)).v
    np.testing.assert_allclose(v, v_lagrange, atol=1e-7 * np.max(np.abs(v_lagrange)))


@pytest.mark.parametrize("q, dq", STATES)
def test_gravity_terms_are_the_gradient_of_the_potential(q, dq):
    """Catches gravity terms with a wrong sign, mass or COM (the potential's gradient, any gravity)."""
    gravity = np.array([0.3, -9.81, 1.2])
    masses = np.array([link.mass for link in CHAIN.links])

    def potential(qq):
        return -np.sum(masses * (_com_positions(qq) @ gravity))

    grad = np.array([(potential(q + EPS * e) - potential(q - EPS * e)) / (2 * EPS) for e in np.eye(4)])
    np.testing.assert_allclose(chain_dynamics(CHAIN, q, dq, gravity).g, grad, atol=1e-8)


def test_bad_joint_kind_is_refused():
    """Catches a DH joint that accepts a kind other than 'R' or 'P'."""
    with pytest.raises(ValueError, match="'R' or 'P'"):
        DHJoint("X", a=0.1, alpha=0.0)


@pytest.mark.parametrize("q, dq", STATES)
def test_a_point_mass_adds_its_own_kinetic_and_potential_energy(q, dq):
    """with_point_mass: the composite link's M and g are the bare chain's plus the
    point's m v.v/2 and -m p.g, the point's motion taken from the bare chain's frames."""
    mass, where = 0.7, np.array([-0.12, 0.04, 0.03])
    links = list(CHAIN.links)
    links[2] = with_point_mass(links[2], mass, where)
    loaded = SerialChain(CHAIN.joints, tuple(links), CHAIN.rotor_inertia, CHAIN.gear_ratio)
    gravity = np.array([0.3, -9.81, 1.2])

    def point(qq):
        frame = chain_kinematics(CHAIN, qq, dq).frames[3]
        return frame[:3, :3] @ where + frame[:3, 3]

    v = (point(q + EPS * dq) - point(q - EPS * dq)) / (2 * EPS)
    bare, both = chain_dynamics(CHAIN, q, dq, gravity), chain_dynamics(loaded, q, dq, gravity)
    np.testing.assert_allclose(0.5 * dq @ both.M @ dq, 0.5 * dq @ bare.M @ dq + 0.5 * mass * v @ v, rtol=1e-8)
    grad = np.array([(point(q + EPS * e) - point(q - EPS * e)) @ gravity / (2 * EPS) for e in np.eye(4)])
    np.testing.assert_allclose(both.g, bare.g - mass * grad, atol=1e-8)
    assert with_point_mass(links[1], 0.0, where) is links[1]
    with pytest.raises(ValueError, match="point mass"):
        with_point_mass(links[1], -1.0, where)
