"""The eight control strategies of the thesis (7.2.6) with the parameters of Tables 6-8 (7.2.10).

All are the unified law (7.21-7.22) with kp = lam^2, kv = 2 lam (7.29-7.30):

* ``PD`` (PDq, PDx): k = 0, ĥ = 0, Ĥ = m*·1 (PD with acceleration feedforward);
* ``TC`` (TCq, TCx): k = 0, Ĥ and ĥ from the model (computed torque, 6.2);
* ``PDMD``, ``TCMD``: the same plus the integral of k sat(s/phi) (sliding modes, 6.3,
  boundary layer 6.3.2).

Suffix ``q``: joint space (the actuated angles, units rad, m* in kg m^2); ``x``: task space
(m, m* in kg).  The joint-space parameters differ between the circle (Table 6) and the
triangle (Table 7): :func:`get_strategy` takes ``trajectory`` ("circle", the default, also used
for ``thesis_circle`` and ``hold``; or "triangle").  Task space has one table (Table 8) for
both.  Table 8 gives k2 = 0 for PDMDx and TCMDx: no sliding term on y.

Two more, not the thesis': ``SMCq`` and ``SMCx``, seed 001's sliding-mode law (section 1.2;
``law = "seed001"``): s = de + lam e, u' = Ĥ (ddr_d + lam de + k sat(s/phi)) + ĥ.  Inside the
boundary layer it is computed torque with kv = lam + k/phi, kp = lam k/phi; outside, the
feedback saturates at k.  It is not the unified law written differently (docs/controller.md,
"Seed 001's sliding-mode law").  Their gains: lam = 60/s as TC; k/phi = 3 lam (a layer three
times stiffer than TC, kp = 3 lam^2, kv = 4 lam), phi = 0.05 m/s (task) or 0.4 rad/s (joint):
on the sliding line de = -lam e the layer is |e| < phi / lam, 0.83 mm or 6.7 mrad (0.8 mm at
the 0.12 m proximal link).  Chosen so, not tuned on the results (docs/controller.md).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

STRATEGY_NAMES = ("PDq", "PDx", "TCq", "TCx", "PDMDq", "PDMDx", "TCMDq", "TCMDx")
#: Seed 001's sliding-mode law on the coupled form (section 1.2), joint and task space.
SEED_STRATEGY_NAMES = ("SMCq", "SMCx")
#: Every strategy :func:`get_strategy` knows: the thesis' eight, then seed 001's.
ALL_STRATEGY_NAMES = STRATEGY_NAMES + SEED_STRATEGY_NAMES
LAWS = ("unified", "seed001")
TABLE_TRAJECTORIES = ("circle", "triangle")


@dataclass(frozen=True)
class Strategy:
    """Parameters of one strategy of the unified law (7.21-7.22).

    Attributes
    ----------
    name : str
    space : {"q", "x"}
        Joint or task space.
    model_based : bool
        True: Ĥ, ĥ from the model (TC); False: Ĥ = m*·1, ĥ = 0 (PD).
    lam : float
        lambda of (7.29-7.30), rad/s.
    m_star : float
        Constant inertia of the PD laws (kg m^2 in joint space, kg in task space); unused by TC.
    phi : float
        Boundary-layer width of sat(s/phi) (6.65), rad/s^2 or m/s^2.
    k : tuple of float
        (k1, k2) sliding gains, rad/s^2 or m/s^2 (per second of integration); (0, 0): no MD term.
    gamma : tuple of float or None
        Adaptation rates of (6.66); None: constant k.
    law : {"unified", "seed001"}
        The thesis' law (7.21-7.22) or seed 001's (section 1.2): s = de + lam e,
        u' = Ĥ (ddr_d + lam de + k sat(s/phi)) + ĥ, no integral.
    """

    name: str
    space: str
    model_based: bool
    lam: float
    m_star: float = 0.0
    phi: float = 1.0
    k: tuple = (0.0, 0.0)
    gamma: tuple | None = None
    law: str = "unified"

    def __post_init__(self):
        if self.law not in LAWS:
            raise ValueError(f"law = {self.law!r} is unknown; valid: {', '.join(LAWS)}")
        if self.law == "seed001" and not self.model_based:
            raise ValueError(f"strategy {self.name}: seed 001's law needs the model (model_based = True)")

    def with_(self, **changes) -> "Strategy":
        return replace(self, **changes)


# Table 6 (joint space, circle), Table 7 (joint space, triangle), Table 8 (task space).
_TABLES = {
    "circle": {
        "PDq": Strategy("PDq", "q", False, 35.0, m_star=3.58e-3),
        "PDMDq": Strategy("PDMDq", "q", False, 35.0, m_star=3.58e-3, phi=20.0, k=(200.0, 200.0)),
        "TCq": Strategy("TCq", "q", True, 60.0),
        "TCMDq": Strategy("TCMDq", "q", True, 60.0, phi=20.0, k=(363.0, 363.0)),
    },
    "triangle": {
        "PDq": Strategy("PDq", "q", False, 25.0, m_star=3.58e-3),
        "PDMDq": Strategy("PDMDq", "q", False, 25.0, m_star=3.58e-3, phi=90.0, k=(200.0, 200.0)),
        "TCq": Strategy("TCq", "q", True, 60.0),
        "TCMDq": Strategy("TCMDq", "q", True, 60.0, phi=20.0, k=(363.0, 363.0)),
    },
}
_TASK = {
    "PDx": Strategy("PDx", "x", False, 70.0, m_star=0.207),
    "PDMDx": Strategy("PDMDx", "x", False, 70.0, m_star=0.207, phi=6.0, k=(70.0, 0.0)),
    "TCx": Strategy("TCx", "x", True, 60.0),
    "TCMDx": Strategy("TCMDx", "x", True, 60.0, phi=6.0, k=(103.0, 0.0)),
    "SMCx": Strategy("SMCx", "x", True, 60.0, phi=0.05, k=(9.0, 9.0), law="seed001"),
}
#: Seed 001's law in joint space: one set for every trajectory.
_SEED_JOINT = {"SMCq": Strategy("SMCq", "q", True, 60.0, phi=0.4, k=(72.0, 72.0), law="seed001")}


def get_strategy(name: str, trajectory: str = "circle") -> Strategy:
    """The preset ``name`` with the parameters of Tables 6-8.

    Parameters
    ----------
    name : str
        One of :data:`ALL_STRATEGY_NAMES`.
    trajectory : str
        "circle" (Table 6; also for thesis_circle and hold) or "triangle" (Table 7);
        only joint-space strategies depend on it.

    Raises
    ------
    ValueError
        Unknown name or trajectory, listing the valid ones.
    """
    if trajectory in ("thesis_circle", "hold"):
        trajectory = "circle"
    if trajectory not in TABLE_TRAJECTORIES:
        raise ValueError(f"trajectory = {trajectory!r}: valid: {', '.join(TABLE_TRAJECTORIES)} "
                         "(thesis_circle and hold use the circle table)")
    if name in _TASK:
        return _TASK[name]
    if name in _SEED_JOINT:
        return _SEED_JOINT[name]
    if name in _TABLES[trajectory]:
        return _TABLES[trajectory][name]
    raise ValueError(f"strategy = {name!r} is unknown; valid: {', '.join(ALL_STRATEGY_NAMES)}")
