"""Translational parallel mechanisms from serial chains: thesis chapter 5.

A platform B_0 that only translates is coupled to n serial chains B_1..B_n
through the constant architecture matrices d, D, E, F (5.12-5.22).  The
generalised coordinates are ``q = [q_0, q_1, ..., q_n]`` with ``q_0`` the
platform's centre of mass (5.5); ``Q#``, ``Q°`` pick the independent and
redundant coordinates out of q (5.52).

This module gives the constraint residual (5.18), A(q) (5.36), b(q, dq)
(5.42), C(q) (5.56), the forward dynamics with Baumgarte stabilisation
(5.66) and the inverse dynamics terms M_M, v_M, g_M and Z (5.67-5.77).

Redundant constraint rows (the 5R has two identical z rows, one per chain)
make ``A Q°`` tall; its inverse in (5.54), (5.67) and (5.69) is the exact
left inverse of a full-column-rank matrix, computed by least squares.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .serial import chain_dynamics, chain_kinematics


@dataclass(frozen=True)
class ParallelMechanism:
    """A translational platform coupled to serial chains (5.1-5.60).

    Parameters
    ----------
    chains : tuple of SerialChain
    platform_mass : float
        m of the platform/end effector (5.7).
    d : ndarray, shape (3n,)
        (5.12, 5.20): ``d_i = [o_i]_{N_0} - [1]_{N_0|B_0} [x_i]_{B_0}``.
    D : ndarray, shape (3n, 3)
        (5.19).
    E : ndarray, shape (3n, 3n)
        (5.13, 5.21): block diagonal of ``E_i = [1]_{N_0|N_i}``.
    F : ndarray, shape (3n, sum nu_i)
        (5.22); zero when there are no affine constraints.
    independent : tuple of int
        Indices of q that form ``q#`` (5.52); the rest form ``q°``.
    actuated : tuple of int
        Indices of q driven by the actuators; ``u' = U u*`` (5.70).
    gravity : ndarray, shape (3,)
        ``[g]_{N_0}``.
    """

    chains: tuple
    platform_mass: float
    d: np.ndarray
    D: np.ndarray
    E: np.ndarray
    F: np.ndarray
    independent: tuple
    actuated: tuple
    gravity: np.ndarray

    @property
    def n_coordinates(self) -> int:
        return 3 + sum(c.dof for c in self.chains)

    @property
    def Q_independent(self) -> np.ndarray:
        """Q# of (5.52)."""
        return np.eye(self.n_coordinates)[:, list(self.independent)]

    @property
    def Q_redundant(self) -> np.ndarray:
        """Q° of (5.52)."""
        rest = [k for k in range(self.n_coordinates) if k not in self.independent]
        return np.eye(self.n_coordinates)[:, rest]

    @property
    def U(self) -> np.ndarray:
        """U of (5.70)."""
        return np.eye(self.n_coordinates)[:, list(self.actuated)]

    def split(self, q):
        """``q -> (q_0, [q_1, ..., q_n])``."""
        q = np.asarray(q, dtype=float)
        parts, start = [], 3
        for chain in self.chains:
            parts.append(q[start:start + chain.dof])
            start += chain.dof
        return q[:3], parts


@dataclass
class MechanismState:
    """Constraint and dynamics terms of the mechanism at (q, dq)."""

    residual: np.ndarray  # q̄(q) (5.18)
    A: np.ndarray         # (5.36)
    b: np.ndarray         # (5.42)
    C: np.ndarray         # (5.56)
    M: np.ndarray         # M'(q) (5.44)
    v: np.ndarray         # v'(q, dq) (5.45)
    g: np.ndarray         # g'(q) (5.46)


def _block_diag(blocks):
    rows = sum(b.shape[0] for b in blocks)
    cols = sum(b.shape[1] for b in blocks)
    out = np.zeros((rows, cols))
    r = c = 0
    for b in blocks:
        out[r:r + b.shape[0], c:c + b.shape[1]] = b
        r += b.shape[0]
        c += b.shape[1]
    return out


def left_inverse_solve(A, B):
    """Solve ``A X = B`` for tall full-column-rank A (exact when consistent)."""
    return np.linalg.lstsq(A, B, rcond=None)[0]


def mechanism_state(mech: ParallelMechanism, q, dq) -> MechanismState:
    """Evaluate q̄, A, b, C, M', v', g' at (q, dq) (5.18-5.56)."""
    q = np.asarray(q, dtype=float)
    dq = np.asarray(dq, dtype=float)
    q0, qs = mech.split(q)
    _, dqs = mech.split(dq)
    kins = [chain_kinematics(c, qi, dqi) for c, qi, dqi in zip(mech.chains, qs, dqs)]
    x = np.concatenate([k.tip for k in kins])                              # (5.23)
    Jv = _block_diag([k.Jv_tip for k in kins])                             # (5.26)
    tip_bias = np.concatenate([k.a_tip_bias for k in kins])                # (5.38)
    q_serial = q[3:]
    residual = mech.D @ q0 - mech.d - mech.E @ x - mech.F @ q_serial        # (5.18)
    A = np.hstack([mech.D, -(mech.E @ Jv + mech.F)])                       # (5.36)
    b = -mech.E @ tip_bias                                                 # (5.42)
    AQo = A @ mech.Q_redundant
    C = mech.Q_independent - mech.Q_redundant @ left_inverse_solve(AQo, A @ mech.Q_independent)  # (5.56)
    blocks_M = [mech.platform_mass * np.eye(3)]
    v = [np.zeros(3)]                                                      # (5.8)
    g = [-mech.platform_mass * mech.gravity]                               # (5.9)
    for chain, qi, dqi, kin, E_i in zip(mech.chains, qs, dqs, kins, _chain_rotations(mech)):
        # Each chain is modelled in its own base frame N_i: gravity rotates into it.
        dyn = chain_dynamics(chain, qi, dqi, E_i.T @ mech.gravity, kin)
        blocks_M.append(dyn.M)
        v.append(dyn.v)
        g.append(dyn.g)
    return MechanismState(residual, A, b, C, _block_diag(blocks_M), np.concatenate(v), np.concatenate(g))


def _chain_rotations(mech: ParallelMechanism):
    """E_i = [1]_{N_0|N_i}, the diagonal blocks of E (5.13)."""
    return [mech.E[3 * i:3 * i + 3, 3 * i:3 * i + 3] for i in range(len(mech.chains))]


def forward_dynamics(mech: ParallelMechanism, q, dq, u_star, baumgarte: float, state: MechanismState | None = None):
    """ddq from (5.66): dynamics projected by C and Baumgarte-stabilised constraints.

    Parameters
    ----------
    u_star : array_like
        Actuator efforts, ``u' = U u*`` (5.70).
    baumgarte : float
        The Baumgarte lambda [1/s]; 0 gives the plain constraint (5.62).
    """
    if state is None:
        state = mechanism_state(mech, q, dq)
    dq = np.asarray(dq, dtype=float)
    u_prime = mech.U @ np.asarray(u_star, dtype=float)
    lhs = np.vstack([state.C.T @ state.M, state.A])
    rhs = np.concatenate([
        state.C.T @ (u_prime - state.v - state.g),
        -state.b - 2.0 * baumgarte * (state.A @ dq) - baumgarte ** 2 * state.residual,
    ])
    return left_inverse_solve(lhs, rhs)


@dataclass
class InverseDynamicsTerms:
    """M_M ddq# + v_M + g_M = Z^T u* (5.74)."""

    M: np.ndarray   # (5.75)
    v: np.ndarray   # (5.76)
    g: np.ndarray   # (5.77)
    Z: np.ndarray   # Z^T = C^T U (5.72)
    c: np.ndarray   # (5.69)


def inverse_dynamics_terms(mech: ParallelMechanism, q, dq, state: MechanismState | None = None) -> InverseDynamicsTerms:
    """The terms of (5.74) at a consistent (q, dq) (5.67-5.77)."""
    if state is None:
        state = mechanism_state(mech, q, dq)
    c = -mech.Q_redundant @ left_inverse_solve(state.A @ mech.Q_redundant, state.b)   # (5.67-5.69)
    M = state.C.T @ state.M @ state.C                                               # (5.75)
    v = state.C.T @ (state.M @ c + state.v)                                         # (5.76)
    g = state.C.T @ state.g                                                         # (5.77)
    Z = (state.C.T @ mech.U).T                                                      # (5.72)
    return InverseDynamicsTerms(M, v, g, Z, c)


def inverse_dynamics(mech: ParallelMechanism, q, dq, ddq_independent, state: MechanismState | None = None):
    """Actuator efforts u* for a motion (5.74); needs as many actuators as dof."""
    terms = inverse_dynamics_terms(mech, q, dq, state)
    return np.linalg.solve(terms.Z.T, terms.M @ ddq_independent + terms.v + terms.g)
