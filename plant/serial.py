"""Serial chains from Denavit-Hartenberg tables: thesis chapter 4.

The recursive kinematics (4.1-4.83) and the dynamics of the links and joints
(4.84-4.87) with the rotor inertias of the actuators (4.139-4.140) for a
serial chain of revolute and prismatic joints in 3-D.

All vectors and matrices are written in the chain's base frame N (the
thesis' ``[.]_N``).  A chain is immutable (:class:`SerialChain`); the
functions take the joint state ``(q, dq)`` and return plain arrays.

Notation (thesis -> code)
-------------------------
``k_{i-1}``       joint axis of joint i                      ``axes[i]``
``o_{i-1}``       origin of frame B_{i-1}                    ``origins[i]``
``J_v``, ``J_w``  tip Jacobians (4.19, 4.38)                 ``Jv_tip``, ``Jw_tip``
``J_v,i``         Jacobian of the centre of mass g_i (4.25)  ``Jv_com[i]``
``J_w,i``         angular Jacobian of link i (4.44)          ``Jw_link[i]``
``Q`` (4.58)      velocity-quadratic tip acceleration        ``a_tip_bias``
``alpha`` (4.77)  velocity-quadratic tip angular accel.      ``alpha_tip_bias``
``G_i`` (4.64)    velocity-quadratic com acceleration        ``a_com_bias[i]``
``alpha_i`` (4.83) velocity-quadratic link angular accel.    ``alpha_link_bias[i]``

Typos of the printed thesis corrected here (verified against finite
differences in ``tests/plant/test_serial.py``):

* (4.63) prints ``dq_j J_v,i,j ^ (...)``; the cross product is with the joint
  axis ``dq_j J_w,j`` (as in 4.57), otherwise the centripetal term vanishes.
* (4.71) defines ``alpha_i`` with ``B_i`` twice; it is the angular
  acceleration of ``B_nu`` relative to ``B_i`` (as 4.33 for velocities).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

REVOLUTE = "R"
PRISMATIC = "P"


@dataclass(frozen=True)
class DHJoint:
    """One row of a Denavit-Hartenberg table (4.1).

    For a revolute joint ``theta`` is an offset added to ``q``; for a
    prismatic joint ``d`` is the offset.
    """

    kind: str
    a: float
    alpha: float
    d: float = 0.0
    theta: float = 0.0

    def __post_init__(self):
        if self.kind not in (REVOLUTE, PRISMATIC):
            raise ValueError(f"joint kind must be 'R' or 'P', got {self.kind!r}")


@dataclass(frozen=True)
class RigidLink:
    """Inertial data of one link.

    Parameters
    ----------
    mass : float
        m_i [kg].
    com : array_like, shape (3,)
        ``[g_i]_{B_i}``: the centre of mass in the link's own DH frame.
    inertia : array_like, shape (3, 3)
        ``I_{g_i}`` about the centre of mass, written in the link's frame.
    """

    mass: float
    com: tuple
    inertia: tuple

    def __post_init__(self):
        object.__setattr__(self, "com", tuple(float(c) for c in np.ravel(self.com)))
        object.__setattr__(
            self, "inertia", tuple(tuple(float(v) for v in row) for row in np.reshape(self.inertia, (3, 3)))
        )


def with_point_mass(link: RigidLink, mass: float, position) -> RigidLink:
    """The link with a point mass rigidly attached: one composite rigid body.

    A counter-mass or a payload (seed 001 (55)-(63)) enters the mass matrix and the
    gravity terms exactly as this composite link does: the masses add, the centre of
    mass is their weighted mean, and the inertia about the new centre follows from the
    parallel-axis theorem applied to both bodies.

    Parameters
    ----------
    link : RigidLink
    mass : float
        The point mass [kg], >= 0.
    position : array_like, shape (3,)
        Where it sits, in the link's own DH frame [m].
    """
    if not (math.isfinite(mass) and mass >= 0.0):
        raise ValueError(f"point mass must be a finite number >= 0 kg, got {mass!r}")
    if mass == 0.0:
        return link
    p = np.asarray(position, dtype=float)
    g = np.asarray(link.com)
    total = link.mass + mass
    com = (link.mass * g + mass * p) / total

    def shifted(m, r):
        """Inertia of a point mass m at offset r (the parallel-axis term)."""
        return m * (np.dot(r, r) * np.eye(3) - np.outer(r, r))

    inertia = np.asarray(link.inertia) + shifted(link.mass, g - com) + shifted(mass, p - com)
    return RigidLink(total, com, inertia)


@dataclass(frozen=True)
class SerialChain:
    """A serial mechanism B of nu joints (thesis chapter 4).

    Parameters
    ----------
    joints : tuple of DHJoint
    links : tuple of RigidLink
    rotor_inertia : tuple of float
        ``J_r_i``: axial inertia of the rotor driving joint i (4.139); the rotor
        spins about ``k_{i-1}`` and sits on link i-1.
    gear_ratio : tuple of float
        ``r_i`` of (4.124), ``q_r = r q``.
    """

    joints: tuple
    links: tuple
    rotor_inertia: tuple = field(default=())
    gear_ratio: tuple = field(default=())

    def __post_init__(self):
        n = len(self.joints)
        if len(self.links) != n:
            raise ValueError(f"{n} joints but {len(self.links)} links")
        if not self.rotor_inertia:
            object.__setattr__(self, "rotor_inertia", (0.0,) * n)
        if not self.gear_ratio:
            object.__setattr__(self, "gear_ratio", (1.0,) * n)
        if len(self.rotor_inertia) != n or len(self.gear_ratio) != n:
            raise ValueError("rotor_inertia and gear_ratio need one entry per joint")

    @property
    def dof(self) -> int:
        return len(self.joints)


def dh_transform(joint: DHJoint, q: float) -> np.ndarray:
    """Homogeneous transform ``[1]^H_{B_{i-1}|B_i}`` of one joint (4.1)."""
    theta = joint.theta + (q if joint.kind == REVOLUTE else 0.0)
    d = joint.d + (q if joint.kind == PRISMATIC else 0.0)
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(joint.alpha), np.sin(joint.alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, joint.a * ct],
            [st, ct * ca, -ct * sa, joint.a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


@dataclass
class ChainKinematics:
    """Everything the recursive kinematics of one chain yields at (q, dq)."""

    frames: np.ndarray          # (nu+1, 4, 4): [1]^H_{N|B_i}, i = 0..nu (4.2)
    tip: np.ndarray             # (3,) [x]_N = [o_nu]_N (4.4)
    Jv_tip: np.ndarray          # (3, nu) (4.13, 4.19)
    Jw_tip: np.ndarray          # (3, nu) (4.32, 4.38)
    a_tip_bias: np.ndarray      # (3,) (4.57-4.58)
    alpha_tip_bias: np.ndarray  # (3,) (4.76-4.77)
    com: np.ndarray             # (nu, 3) [g_i]_N (4.5)
    Jv_com: np.ndarray          # (nu, 3, nu) (4.20, 4.25)
    Jw_link: np.ndarray         # (nu, 3, nu) (4.39, 4.44)
    a_com_bias: np.ndarray      # (nu, 3) (4.63-4.64)
    alpha_link_bias: np.ndarray  # (nu, 3) (4.82-4.83)
    omega_link: np.ndarray      # (nu, 3) omega_i^* (4.43)


def _joint_columns(kind: str, axis: np.ndarray, origin: np.ndarray, point: np.ndarray):
    """Columns (J_v, J_w) of one joint for a point (4.13, 4.20, 4.32)."""
    if kind == PRISMATIC:
        return axis, np.zeros(3)
    return np.cross(axis, point - origin), axis


def _velocity_quadratic(kind, dq_j, axis, jv_col, v_rel):
    """One term (4.57)/(4.63): dq_j J_w,j ^ (dq_j J_v,j + 2 v_rel)."""
    if kind == PRISMATIC:
        return np.zeros(3)
    return dq_j * np.cross(axis, dq_j * jv_col + 2.0 * v_rel)


def chain_kinematics(chain: SerialChain, q, dq) -> ChainKinematics:
    """Recursive position, velocity and acceleration kinematics (4.1-4.83).

    Parameters
    ----------
    chain : SerialChain
    q, dq : array_like, shape (nu,)
        Joint displacements and rates.
    """
    q = np.asarray(q, dtype=float)
    dq = np.asarray(dq, dtype=float)
    nu = chain.dof
    frames = np.empty((nu + 1, 4, 4))
    frames[0] = np.eye(4)
    for i, joint in enumerate(chain.joints):                       # (4.2)
        frames[i + 1] = frames[i] @ dh_transform(joint, q[i])
    axes = frames[:nu, :3, 2]       # k_{i-1}, i = 1..nu  (4.3)
    origins = frames[:nu, :3, 3]    # o_{i-1}
    kinds = [j.kind for j in chain.joints]
    tip = frames[nu, :3, 3].copy()  # (4.4)

    def point_terms(point, upto):
        """J_v, J_w, velocity-quadratic linear and angular terms of a point
        carried by link ``upto`` (joints 1..upto move it), by the backward
        recursions (4.17, 4.36, 4.55, 4.74)."""
        Jv = np.zeros((3, nu))
        Jw = np.zeros((3, nu))
        for j in range(upto):
            Jv[:, j], Jw[:, j] = _joint_columns(kinds[j], axes[j], origins[j], point)
        v_rel = np.zeros(3)       # velocity of the point relative to B_j (4.17)
        w_rel = np.zeros(3)       # angular velocity of the body relative to B_j (4.36)
        a_bias = np.zeros(3)
        alpha_bias = np.zeros(3)
        for j in range(upto - 1, -1, -1):
            a_bias += _velocity_quadratic(kinds[j], dq[j], axes[j], Jv[:, j], v_rel)  # (4.57)
            if kinds[j] == REVOLUTE:
                alpha_bias += dq[j] * np.cross(axes[j], w_rel)                        # (4.76)
            v_rel = v_rel + Jv[:, j] * dq[j]
            w_rel = w_rel + Jw[:, j] * dq[j]
        return Jv, Jw, a_bias, alpha_bias, w_rel

    Jv_tip, Jw_tip, a_tip_bias, alpha_tip_bias, _ = point_terms(tip, nu)
    com = np.empty((nu, 3))
    Jv_com = np.empty((nu, 3, nu))
    Jw_link = np.empty((nu, 3, nu))
    a_com_bias = np.empty((nu, 3))
    alpha_link_bias = np.empty((nu, 3))
    omega_link = np.empty((nu, 3))
    for i, link in enumerate(chain.links):
        com[i] = frames[i + 1, :3, :3] @ np.array(link.com) + frames[i + 1, :3, 3]   # (4.5)
        (Jv_com[i], Jw_link[i], a_com_bias[i], alpha_link_bias[i], omega_link[i]) = point_terms(
            com[i], i + 1
        )
    return ChainKinematics(
        frames, tip, Jv_tip, Jw_tip, a_tip_bias, alpha_tip_bias,
        com, Jv_com, Jw_link, a_com_bias, alpha_link_bias, omega_link,
    )


@dataclass
class ChainDynamics:
    """Terms of M*(q) ddq + v*(q, dq) + g*(q) = u* (4.138)."""

    M: np.ndarray   # (nu, nu) (4.85 + 4.139)
    v: np.ndarray   # (nu,) (4.86 + 4.140, without friction)
    g: np.ndarray   # (nu,) (4.87)


def chain_dynamics(chain: SerialChain, q, dq, gravity, kin: ChainKinematics | None = None) -> ChainDynamics:
    """Generalised inertia, velocity-quadratic and gravity terms (4.84-4.87).

    The rotor inertias of (4.139-4.140) are included; friction torques
    (the ``r zeta(r dq)`` of 4.140) belong to the drive, not the plant.

    Parameters
    ----------
    gravity : array_like, shape (3,)
        The gravity vector written in the chain's base frame.
    kin : ChainKinematics, optional
        Reuse kinematics already computed at (q, dq).
    """
    if kin is None:
        kin = chain_kinematics(chain, q, dq)
    dq = np.asarray(dq, dtype=float)
    gravity = np.asarray(gravity, dtype=float)
    nu = chain.dof
    M = np.zeros((nu, nu))
    v = np.zeros(nu)
    g = np.zeros(nu)
    for i, link in enumerate(chain.links):
        R = kin.frames[i + 1, :3, :3]
        inertia_N = R @ np.array(link.inertia) @ R.T                       # I_i = [I_gi]_{N|N}
        Jv, Jw = kin.Jv_com[i], kin.Jw_link[i]
        w = kin.omega_link[i]
        M += link.mass * Jv.T @ Jv + Jw.T @ inertia_N @ Jw                 # (4.85)
        v += link.mass * Jv.T @ kin.a_com_bias[i] + Jw.T @ (
            inertia_N @ kin.alpha_link_bias[i] + np.cross(w, inertia_N @ w)
        )                                                                  # (4.86)
        g -= link.mass * Jv.T @ gravity                                    # (4.87)
    for i in range(nu):
        Jr = chain.rotor_inertia[i]
        if Jr == 0.0:
            continue
        # Rotor i sits on link i-1 and spins about k_{i-1} (4.127-4.137).
        axis = kin.frames[i, :3, 2]
        Jw_r = np.zeros((3, nu))                                           # (4.130)
        if i > 0:
            Jw_r[:, :i] = kin.Jw_link[i - 1][:, :i]
        Jw_r[:, i] = chain.gear_ratio[i] * axis
        omega_r = Jw_r @ dq                                                # (4.129)
        alpha_r = np.zeros(3)                                              # (4.137)
        if i > 0:
            alpha_r = kin.alpha_link_bias[i - 1] + np.cross(kin.omega_link[i - 1], dq[i] * Jw_r[:, i])
        inertia_r = Jr * np.outer(axis, axis)   # axial inertia only: transverse data are unknown
        M += Jw_r.T @ inertia_r @ Jw_r                                     # (4.139)
        v += Jw_r.T @ (inertia_r @ alpha_r + np.cross(omega_r, inertia_r @ omega_r))  # (4.140)
    return ChainDynamics(M, v, g)
