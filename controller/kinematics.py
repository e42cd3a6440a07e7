"""Scalar closed-form 5R kinematics for the position controller (world frame).

The controller runs every 1 ms on scalars; numpy calls on 2x2 arrays cost about
a microsecond each, so this module re-states, with ``math`` only, the closed-form
kinematics of :mod:`plant.fivebar` (seed 002 eq. 1-20): inverse kinematics in
the "elbows outward" working mode, direct kinematics, the Jacobians J_X, J_Theta
of ``J_X dX + J_Theta dq = 0`` (002 eq. 15-17) and their time derivatives.
``tests/test_controller_kinematics.py`` checks every function against
:mod:`plant.fivebar` and :func:`plant.parallel.mechanism_state` (C and c of
5.56, 5.69).

Change of variables x = FK(q) used by the joint-space controller:

* ``dx = J dq`` with ``J = -J_X^-1 J_Theta``;
* ``ddx = J ddq + beta`` with ``beta = dJ dq = -J_X^-1 (dJ_X dx + dJ_Theta dq)``,
  from differentiating ``J_X dx + J_Theta dq = 0``;
* the actuator power balance ``tau . dq = F . dx`` gives ``tau = J^T F`` for a
  generalised force F on x: this equals ``u* = Z^-T F`` of (5.72) once chain 2's
  mirrored axis is accounted for (``tau2 = -u*_theta21``).
"""
from __future__ import annotations

import math

from plant.fivebar import KinematicsError
from plant.presets import FiveBarParams


class Kinematics:
    """Closed-form kinematics of one 5R geometry.

    Parameters
    ----------
    params : FiveBarParams
        Only the lengths l0, l1, l2 of both chains are used.
    """

    def __init__(self, params: FiveBarParams):
        self.l0 = float(params.l0)
        self.l11, self.l12 = float(params.chain1.l1), float(params.chain1.l2)
        self.l21, self.l22 = float(params.chain2.l1), float(params.chain2.l2)

    # --- positions ------------------------------------------------------------
    def inverse(self, x: float, y: float):
        """World link angles (phi11, phi12, phi21, phi22) reaching (x, y), elbows outward (002 eq. 1-6, 12).

        Raises
        ------
        KinematicsError
            If (x, y) is out of reach of a chain.
        """
        p11, p12 = _chain_ik(self.l11, self.l12, x - self.l0, y, 1.0)
        p21, p22 = _chain_ik(self.l21, self.l22, x + self.l0, y, -1.0)
        return p11, p12, p21, p22

    def margin(self, x: float, y: float) -> float:
        """Singularity margin of (x, y): min |sin| of both elbow angles and of the distal-link angle.

        Same measure as :func:`plant.fivebar.singularity` ``.margin``.
        """
        p11, p12, p21, p22 = self.inverse(x, y)
        return min(abs(math.sin(p12 - p11)), abs(math.sin(p22 - p21)), abs(math.sin(p12 - p22)))

    def forward(self, q1: float, q2: float):
        """End effector (x, y) from the actuated angles (002 eq. 7-11), the assembly of :func:`plant.fivebar.direct_kinematics`."""
        a1x, a1y = self.l0 + self.l11 * math.cos(q1), self.l11 * math.sin(q1)
        a2x, a2y = -self.l0 + self.l21 * math.cos(q2), self.l21 * math.sin(q2)
        dx, dy = a1x - a2x, a1y - a2y
        dist2 = dx * dx + dy * dy
        dist = math.sqrt(dist2)
        r1, r2 = self.l12, self.l22
        if dist == 0.0 or dist > r1 + r2 or dist < abs(r1 - r2):
            raise KinematicsError(f"no assembly for q1={q1:.6g}, q2={q2:.6g} rad (elbow distance {dist:.6g} m)")
        along = (dist2 + r2 * r2 - r1 * r1) / (2.0 * dist)
        height = math.sqrt(max(r2 * r2 - along * along, 0.0))
        ux, uy = dx / dist, dy / dist
        return a2x + along * ux - height * uy, a2y + along * uy + height * ux

    # --- Jacobians ---------------------------------------------------------------
    def jacobians(self, x, y, q1, q2):
        """Entries of J_X = [[a, b], [c, d]] and the diagonal (t1, t2) of J_Theta (002 eq. 15-17)."""
        c1, s1, c2, s2 = math.cos(q1), math.sin(q1), math.cos(q2), math.sin(q2)
        a = x - self.l0 - self.l11 * c1
        b = y - self.l11 * s1
        c = x + self.l0 - self.l21 * c2
        d = y - self.l21 * s2
        t1 = self.l11 * ((x - self.l0) * s1 - y * c1)
        t2 = self.l21 * ((x + self.l0) * s2 - y * c2)
        return a, b, c, d, t1, t2

    def jacobian(self, x, y, q1, q2):
        """J = -J_X^-1 J_Theta as a tuple (J00, J01, J10, J11): dx = J dq."""
        a, b, c, d, t1, t2 = self.jacobians(x, y, q1, q2)
        det = a * d - b * c
        return -d * t1 / det, b * t2 / det, c * t1 / det, -a * t2 / det

    def _bias_rhs(self, x, y, q1, q2, dx, dy, dq1, dq2):
        """dJ_X dx + dJ_Theta dq (the velocity-quadratic part of the differentiated constraint)."""
        c1, s1, c2, s2 = math.cos(q1), math.sin(q1), math.cos(q2), math.sin(q2)
        da1x, da1y = -self.l11 * dq1 * s1, self.l11 * dq1 * c1
        da2x, da2y = -self.l21 * dq2 * s2, self.l21 * dq2 * c2
        r1 = (dx - da1x) * dx + (dy - da1y) * dy
        r2 = (dx - da2x) * dx + (dy - da2y) * dy
        r1 += self.l11 * (dx * s1 + (x - self.l0) * c1 * dq1 - dy * c1 + y * s1 * dq1) * dq1
        r2 += self.l21 * (dx * s2 + (x + self.l0) * c2 * dq2 - dy * c2 + y * s2 * dq2) * dq2
        return r1, r2

    def task_state(self, q1, q2, dq1, dq2, ddq1, ddq2):
        """(x, y, dx, dy, ddx, ddy, J, beta) from joint measurements.

        ``ddx = J ddq + beta`` (module docstring); J as (J00, J01, J10, J11).
        """
        x, y = self.forward(q1, q2)
        a, b, c, d, t1, t2 = self.jacobians(x, y, q1, q2)
        det = a * d - b * c
        J = (-d * t1 / det, b * t2 / det, c * t1 / det, -a * t2 / det)
        dx = J[0] * dq1 + J[1] * dq2
        dy = J[2] * dq1 + J[3] * dq2
        r1, r2 = self._bias_rhs(x, y, q1, q2, dx, dy, dq1, dq2)
        beta = (-(d * r1 - b * r2) / det, -(-c * r1 + a * r2) / det)
        ddx = J[0] * ddq1 + J[1] * ddq2 + beta[0]
        ddy = J[2] * ddq1 + J[3] * ddq2 + beta[1]
        return x, y, dx, dy, ddx, ddy, J, beta

    def joint_reference(self, x, y, dx, dy, ddx, ddy, angles=None):
        """(q1, q2, dq1, dq2, ddq1, ddq2) following the task-space motion (x, dx, ddx).

        ``dq = -J_Theta^-1 J_X dx``, ``ddq = -J_Theta^-1 (J_X ddx + dJ_X dx + dJ_Theta dq)``.
        ``angles``: the result of :meth:`inverse` at (x, y) if already computed.
        """
        p11, _, p21, _ = self.inverse(x, y) if angles is None else angles
        a, b, c, d, t1, t2 = self.jacobians(x, y, p11, p21)
        dq1 = -(a * dx + b * dy) / t1
        dq2 = -(c * dx + d * dy) / t2
        r1, r2 = self._bias_rhs(x, y, p11, p21, dx, dy, dq1, dq2)
        ddq1 = -(a * ddx + b * ddy + r1) / t1
        ddq2 = -(c * ddx + d * ddy + r2) / t2
        return p11, p21, dq1, dq2, ddq1, ddq2

    def thesis_rates(self, x, y, angles, dx, dy):
        """dq of the thesis' q (7.12) for the end-effector velocity (dx, dy): C(q) dq# of (5.56).

        ``angles``: world link angles (phi11, phi12, phi21, phi22) at (x, y).
        Chain k's tip velocity l1 dphi_k1 n(phi_k1) + l2 dphi_k2 n(phi_k2) = dx gives both
        link rates (n(phi) = (-sin phi, cos phi)); theta11 = phi11, theta12 = phi12 - phi11,
        theta21 = pi - phi21, theta22 = phi21 - phi22.
        """
        p11, p12, p21, p22 = angles
        w11, w12 = _link_rates(self.l11, self.l12, p11, p12, dx, dy)
        w21, w22 = _link_rates(self.l21, self.l22, p21, p22, dx, dy)
        return [dx, dy, 0.0, w11, w12 - w11, -w21, w21 - w22]


def _chain_ik(l1, l2, px, py, elbow_sign):
    r2 = px * px + py * py
    cos_b = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    if not -1.0 <= cos_b <= 1.0:
        raise KinematicsError(f"point out of reach of a chain (distance {math.sqrt(r2):.6g} m)")
    beta = elbow_sign * math.acos(cos_b)
    phi1 = math.atan2(py, px) - math.atan2(l2 * math.sin(beta), l1 + l2 * math.cos(beta))
    return phi1, phi1 + beta


def _link_rates(l1, l2, p1, p2, dx, dy):
    """Solve l1 w1 n(p1) + l2 w2 n(p2) = (dx, dy) for (w1, w2)."""
    m00, m01 = -l1 * math.sin(p1), -l2 * math.sin(p2)
    m10, m11 = l1 * math.cos(p1), l2 * math.cos(p2)
    det = m00 * m11 - m01 * m10
    return (m11 * dx - m01 * dy) / det, (-m10 * dx + m00 * dy) / det
