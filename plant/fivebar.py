"""The 5R "articulated pentagon" (thesis 7.1) and its closed-form kinematics.

Two functions of this module build the mechanism for the general algorithm:
:func:`build_mechanism` turns :class:`~plant.presets.FiveBarParams` into the
DH tables of Table 2 and the architecture matrices d, D, E, F of (7.8-7.11),
with ``q = [x, y, z, theta11, theta12, theta21, theta22]`` (7.12),
``q# = [x, y]`` (7.13).  Chain 2 is modelled, as in the thesis, in a frame
mirrored by ``E2 = diag(-1, 1, -1)`` (7.4); :func:`world_angles` and
:func:`thesis_coordinates` convert to and from the world convention of the
interface (angles counter-clockwise from +x, chain 1 at (+l0, 0)).

The rest is the closed-form kinematics of seed 002 in world coordinates, computed by the C
kernel ``kernels/src/kinematics5r.c`` (binding :mod:`plant.kinematics5r`):
inverse kinematics in the "elbows outward" working mode (002 eq. 1-6),
direct kinematics (eq. 7-11), passive angles (eq. 12), the Jacobians J_X and
J_Theta (eq. 15-17; eq. 16 prints ``y_p - l_2 s_11`` where ``l_1`` is meant),
singularity measures and a workspace map (thesis fig. 11).
"""
from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass

import numpy as np

from . import kinematics5r as k5r
from .parallel import ParallelMechanism
from .presets import ChainParams, FiveBarParams
from .serial import REVOLUTE, DHJoint, RigidLink, SerialChain, with_point_mass

#: E_2 of (7.4): chain 2's base frame seen from the world frame.
MIRROR = np.diag([-1.0, 1.0, -1.0])

#: Index of each coordinate in q (7.12).
X, Y, Z, TH11, TH12, TH21, TH22 = range(7)


class KinematicsError(ValueError):
    """A point or a configuration the mechanism cannot take."""


def _rr_chain(c: ChainParams) -> SerialChain:
    """The RR chain of Table 2; link frames sit at the distal joint of each link.

    The counter-masses (seed 001 (55)-(64)) are point masses on the links' lines at
    :meth:`~plant.presets.ChainParams.counter_offsets` from the proximal joints, each link
    and its counter-mass one composite rigid body (:func:`plant.serial.with_point_mass`).
    """
    joints = (DHJoint(REVOLUTE, a=c.l1, alpha=0.0), DHJoint(REVOLUTE, a=c.l2, alpha=0.0))
    L1, L2 = c.counter_offsets()
    links = (
        with_point_mass(RigidLink(c.m1, (c.lg1 - c.l1, 0.0, 0.0), np.diag([0.0, c.Jz1, c.Jz1])),
                        c.counter_mass1, (L1 - c.l1, 0.0, 0.0)),
        with_point_mass(RigidLink(c.m2, (c.lg2 - c.l2, 0.0, 0.0), np.diag([0.0, c.Jz2, c.Jz2])),
                        c.counter_mass2, (L2 - c.l2, 0.0, 0.0)),
    )
    return SerialChain(joints, links, rotor_inertia=(c.J_rotor, 0.0))


def build_mechanism(params: FiveBarParams) -> ParallelMechanism:
    """The 5R as a translational parallel mechanism (7.1-7.16)."""
    params.validate()
    l0 = params.l0
    d = np.array([l0, 0.0, 0.0, -l0, 0.0, 0.0])                        # (7.8)
    D = np.vstack([np.eye(3), np.eye(3)])                               # (7.9)
    E = np.zeros((6, 6))                                                # (7.10)
    E[:3, :3] = np.eye(3)
    E[3:, 3:] = MIRROR
    F = np.zeros((6, 4))                                                # (7.11)
    return ParallelMechanism(
        chains=(_rr_chain(params.chain1), _rr_chain(params.chain2)),
        platform_mass=params.m0,
        d=d, D=D, E=E, F=F,
        independent=(X, Y),                                             # (7.13-7.16)
        actuated=(TH11, TH21),
        gravity=np.asarray(params.gravity, dtype=float),
    )


# --- world <-> thesis coordinates -------------------------------------------

def world_angles(q) -> tuple[float, float]:
    """Actuated angles (q1, q2) in the world convention from the thesis' q."""
    return q[TH11], math.pi - q[TH21]


def world_rates(dq) -> tuple[float, float]:
    """(dq1, dq2) in the world convention."""
    return dq[TH11], -dq[TH21]


def thesis_torques(tau1: float, tau2: float) -> np.ndarray:
    """u* on (theta11, theta21): chain 2's mirrored axis points along -z."""
    return np.array([tau1, -tau2])


def world_torques(u_star) -> tuple[float, float]:
    """Inverse of :func:`thesis_torques`."""
    return u_star[0], -u_star[1]


# --- closed-form kinematics in world coordinates ------------------------------

def bases(params: FiveBarParams) -> np.ndarray:
    """Base joints of chain 1 and chain 2, shape (2, 2)."""
    return np.array([[params.l0, 0.0], [-params.l0, 0.0]])


def inverse_kinematics(params: FiveBarParams, x: float, y: float) -> np.ndarray:
    """World link angles ``[phi11, phi12, phi21, phi22]`` reaching (x, y), elbows outward.

    phi11 = q1 and phi21 = q2 are the actuated angles; phi12, phi22 the
    absolute angles of the distal links (002 eq. 1-6, 12).

    Raises
    ------
    KinematicsError
        If (x, y) is outside the workspace.
    """
    if not (math.isfinite(x) and math.isfinite(y)):
        raise KinematicsError(f"point ({x!r}, {y!r}) is not finite")
    # A ctypes array viewed by numpy: cheaper per call than a numpy buffer's ctypes pointer.
    angles, distance = (ctypes.c_double * 4)(), ctypes.c_double()
    if k5r.inverse(k5r.geometry(params), x, y, angles, ctypes.byref(distance)) != k5r.OK:
        raise KinematicsError(f"point (x={x:.6g}, y={y:.6g}) is outside the workspace: "
                              f"point out of reach of a chain (distance {distance.value:.6g} m)")
    return np.frombuffer(angles)


def elbows(params: FiveBarParams, q1: float, q2: float) -> np.ndarray:
    """Elbow points A1, A2 for actuated angles (q1, q2), shape (2, 2)."""
    b = bases(params)
    return np.array([
        b[0] + params.chain1.l1 * np.array([math.cos(q1), math.sin(q1)]),
        b[1] + params.chain2.l1 * np.array([math.cos(q2), math.sin(q2)]),
    ])


def direct_kinematics(params: FiveBarParams, q1: float, q2: float) -> np.ndarray:
    """End-effector (x, y) from the actuated angles (002 eq. 7-11).

    The assembly mode is the one of the thesis' figure: the tip lies to the
    left of the line from chain 2's elbow to chain 1's elbow (above the
    elbows when chain 1's elbow is on the right).
    """
    x, y, distance = ctypes.c_double(), ctypes.c_double(), ctypes.c_double()
    if k5r.forward(k5r.geometry(params), q1, q2, ctypes.byref(x), ctypes.byref(y), ctypes.byref(distance)) != k5r.OK:
        raise KinematicsError(f"no assembly for q1={q1:.6g}, q2={q2:.6g} rad (elbow distance {distance.value:.6g} m)")
    return np.array([x.value, y.value])


def jacobians(params: FiveBarParams, x: float, y: float, q1: float, q2: float):
    """J_X and J_Theta of ``J_X dX + J_Theta dTheta = 0`` (002 eq. 15-17), world frame."""
    jx, jt = (ctypes.c_double * 4)(), (ctypes.c_double * 2)()
    k5r.jacobians(k5r.geometry(params), x, y, q1, q2, jx, jt)
    return np.frombuffer(jx).reshape(2, 2), np.diag(np.frombuffer(jt))


def joint_rates(params: FiveBarParams, x, y, q1, q2, dx, dy) -> np.ndarray:
    """(dq1, dq2) = -J_Theta^-1 J_X (dx, dy) (002 eq. 15)."""
    JX, JT = jacobians(params, x, y, q1, q2)
    return -np.linalg.solve(JT, JX @ np.array([dx, dy]))


@dataclass(frozen=True)
class Singularity:
    """Normalised singularity measures, each in [-1, 1]; 0 is singular.

    ``serial1``, ``serial2``: sine of the elbow angle of each chain
    (det J_Theta = 0: a chain stretched or folded, the tip cannot move along
    it).  ``parallel``: sine of the angle between the two distal links
    (det J_X = 0: the actuators cannot hold the tip in one direction).
    """

    serial1: float
    serial2: float
    parallel: float

    @property
    def margin(self) -> float:
        """The smallest |measure|: the distance to the nearest singularity."""
        return min(abs(self.serial1), abs(self.serial2), abs(self.parallel))


def singularity(params: FiveBarParams, x: float, y: float) -> Singularity:
    """Singularity measures at a workspace point (working mode)."""
    p11, p12, p21, p22 = inverse_kinematics(params, x, y)
    return Singularity(
        serial1=math.sin(p12 - p11),
        serial2=math.sin(p22 - p21),
        parallel=math.sin(p12 - p22),
    )


#: Default width of the near-singular band (thesis fig. 11, yellow): points
#: whose :attr:`Singularity.margin` is below it.  0.1 is ~5.7 degrees from a
#: singular alignment, where the torque or speed amplification exceeds 10x
#: its value at a well-conditioned pose.
NEAR_SINGULAR_MARGIN = 0.1


@dataclass(frozen=True)
class WorkspaceMap:
    """A grid over the plane: ``status`` is 0 outside, 1 inside, 2 near-singular."""

    x: np.ndarray
    y: np.ndarray
    margin: np.ndarray   # NaN outside the workspace
    status: np.ndarray

    OUTSIDE, INSIDE, NEAR_SINGULAR = 0, 1, 2


def workspace_map(params: FiveBarParams, step: float = 0.0025, band: float = NEAR_SINGULAR_MARGIN,
                  extent=None) -> WorkspaceMap:
    """Workspace and near-singular band on a square grid (thesis fig. 11)."""
    reach = max(params.chain1.l1 + params.chain1.l2, params.chain2.l1 + params.chain2.l2)
    if extent is None:
        extent = (-params.l0 - reach, params.l0 + reach, -reach, reach)
    xs = np.arange(extent[0], extent[1] + step / 2, step)
    ys = np.arange(extent[2], extent[3] + step / 2, step)
    margin = np.full((ys.size, xs.size), np.nan)
    # One geometry and one angle buffer for the whole grid: the C calls dominate.
    g, angles, distance = k5r.geometry(params), (ctypes.c_double * 4)(), ctypes.c_double()
    for iy, y in enumerate(ys.tolist()):
        for ix, x in enumerate(xs.tolist()):
            if k5r.inverse(g, x, y, angles, ctypes.byref(distance)) == k5r.OK:
                margin[iy, ix] = k5r.margin(angles)
    status = np.where(np.isnan(margin), WorkspaceMap.OUTSIDE,
                      np.where(margin < band, WorkspaceMap.NEAR_SINGULAR, WorkspaceMap.INSIDE))
    return WorkspaceMap(xs, ys, margin, status)


# --- consistent states of the general model ------------------------------------

def thesis_coordinates(params: FiveBarParams, x: float, y: float) -> np.ndarray:
    """The thesis' q (7.12) for the end effector at (x, y), working mode."""
    p11, p12, p21, p22 = inverse_kinematics(params, x, y)
    th21 = math.pi - p21
    th22 = (math.pi - p22) - th21
    return np.array([x, y, 0.0, p11, p12 - p11, th21, th22])
