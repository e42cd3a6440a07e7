"""The 5R's closed-form kinematics for the position controller (world frame), from the C kernel
``kernels/src/kinematics5r.c`` (binding: :mod:`plant.kinematics5r`) (seed 002 eq. 1-20), which the law itself uses.

Inverse kinematics in the "elbows outward" working mode, direct kinematics, the Jacobians
J_X, J_Theta of ``J_X dX + J_Theta dq = 0`` (002 eq. 15-17) and their time derivatives, the
thesis' coordinates (7.12) and rates (5.56).  ``tests/kernels/test_kernels_law.py`` and
``tests/controller/test_controller_kinematics.py`` hold them against the general algorithm
(:mod:`plant.serial`, :mod:`plant.parallel`) and :mod:`plant.fivebar`.

Change of variables x = FK(q) used by the joint-space controller:

* ``dx = J dq`` with ``J = -J_X^-1 J_Theta``;
* ``ddx = J ddq + beta`` with ``beta = dJ dq = -J_X^-1 (dJ_X dx + dJ_Theta dq)``,
  from differentiating ``J_X dx + J_Theta dq = 0``;
* the actuator power balance ``tau . dq = F . dx`` gives ``tau = J^T F`` for a
  generalised force F on x: this equals ``u* = Z^-T F`` of (5.72) once chain 2's
  mirrored axis is accounted for (``tau2 = -u*_theta21``).
"""
from __future__ import annotations

import ctypes

import numpy as np

from plant import kinematics5r as k5r
from plant.fivebar import KinematicsError
from plant.presets import FiveBarParams

_d = ctypes.c_double
_D = ctypes.POINTER(ctypes.c_double)


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

    def geometry(self) -> k5r.Geometry:
        """The lengths as the kernels' ``pc_5r_geometry``."""
        return k5r.Geometry(self.l0, self.l11, self.l12, self.l21, self.l22)

    # --- positions ------------------------------------------------------------
    def inverse(self, x: float, y: float):
        """World link angles (phi11, phi12, phi21, phi22) reaching (x, y), elbows outward (002 eq. 1-6, 12).

        Raises
        ------
        KinematicsError
            If (x, y) is out of reach of a chain.
        """
        angles, distance = (_d * 4)(), _d()
        if k5r.inverse(self.geometry(), x, y, angles, ctypes.byref(distance)) != k5r.OK:
            raise KinematicsError(f"point out of reach of a chain (distance {distance.value:.6g} m)")
        return tuple(angles)

    def margin(self, x: float, y: float) -> float:
        """Singularity margin of (x, y): min |sin| of both elbow angles and of the distal-link angle.

        Same measure as :func:`plant.fivebar.singularity` ``.margin``.
        """
        return k5r.margin((_d * 4)(*self.inverse(x, y)))

    def forward(self, q1: float, q2: float):
        """End effector (x, y) from the actuated angles (002 eq. 7-11), the assembly of
        :func:`plant.fivebar.direct_kinematics`.

        Raises
        ------
        KinematicsError
            If the distal links cannot meet.
        """
        x, y, distance = _d(), _d(), _d()
        if k5r.forward(self.geometry(), q1, q2, ctypes.byref(x), ctypes.byref(y), ctypes.byref(distance)) != k5r.OK:
            raise KinematicsError(no_assembly(q1, q2, distance.value))
        return x.value, y.value

    # --- Jacobians ---------------------------------------------------------------
    def jacobians(self, x, y, q1, q2):
        """Entries of J_X = [[a, b], [c, d]] and the diagonal (t1, t2) of J_Theta (002 eq. 15-17)."""
        jx, jt = (_d * 4)(), (_d * 2)()
        k5r.jacobians(self.geometry(), x, y, q1, q2, jx, jt)
        return (*jx, *jt)

    def jacobian(self, x, y, q1, q2):
        """J = -J_X^-1 J_Theta as a tuple (J00, J01, J10, J11): dx = J dq."""
        a, b, c, d, t1, t2 = self.jacobians(x, y, q1, q2)
        det = a * d - b * c
        return -d * t1 / det, b * t2 / det, c * t1 / det, -a * t2 / det

    def task_state(self, q1, q2, dq1, dq2, ddq1, ddq2):
        """(x, y, dx, dy, ddx, ddy, J, beta) from joint measurements.

        ``ddx = J ddq + beta`` (module docstring); J as (J00, J01, J10, J11).

        Raises
        ------
        KinematicsError
            Without assembly, or at a parallel singularity (det J_X = 0).
        """
        t = k5r.Task()
        rc = k5r.task_state(self.geometry(), q1, q2, dq1, dq2, ddq1, ddq2, ctypes.byref(t))
        if rc == k5r.NO_ASSEMBLY:
            raise KinematicsError(no_assembly(q1, q2, t.distance))
        if rc != k5r.OK:
            raise KinematicsError(f"q1={q1:.6g}, q2={q2:.6g} rad is a parallel singularity (det J_X = 0)")
        return t.x, t.y, t.dx, t.dy, t.ddx, t.ddy, tuple(t.J), tuple(t.beta)

    def joint_reference(self, x, y, dx, dy, ddx, ddy, angles=None):
        """(q1, q2, dq1, dq2, ddq1, ddq2) following the task-space motion (x, dx, ddx).

        ``dq = -J_Theta^-1 J_X dx``, ``ddq = -J_Theta^-1 (J_X ddx + dJ_X dx + dJ_Theta dq)``.
        ``angles``: the result of :meth:`inverse` at (x, y) if already computed.
        """
        p11, _, p21, _ = self.inverse(x, y) if angles is None else angles
        joint = (_d * 6)()
        if k5r.joint_reference(self.geometry(), x, y, dx, dy, ddx, ddy, p11, p21, joint) != k5r.OK:
            raise KinematicsError(f"(x, y) = ({x:.6g}, {y:.6g}) m: a chain is stretched or folded (J_Theta singular)")
        return tuple(joint)

    def thesis_state(self, x, y, dx, dy):
        """The thesis' q (7.12) and dq = C(q) dq# (5.56) of the end effector at (x, y) moving at
        (dx, dy), as two arrays of 7: theta11 = phi11, theta12 = phi12 - phi11, theta21 = pi - phi21,
        theta22 = phi21 - phi22.

        Raises
        ------
        KinematicsError
            If (x, y) is out of reach of a chain.
        """
        q, dq, distance = np.empty(7), np.empty(7), _d()
        if k5r.thesis_state(self.geometry(), x, y, dx, dy, q.ctypes.data_as(_D), dq.ctypes.data_as(_D),
                         ctypes.byref(distance)) != k5r.OK:
            raise KinematicsError(f"point out of reach of a chain (distance {distance.value:.6g} m)")
        return q, dq


def no_assembly(q1, q2, distance) -> str:
    """The text of a pose the distal links cannot close."""
    return f"no assembly for q1={q1:.6g}, q2={q2:.6g} rad (elbow distance {distance:.6g} m)"
