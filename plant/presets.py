"""Parameters of the 5R mechanism: the single source of truth.

``thesis_sim`` is Table 3 of the thesis (both chains equal, no rotors);
``bench`` is Tables 4-5 with the rotor inertias of Tables 16 and 18 (the
motor presets ``motor1``/``motor2``) on the actuated joints.

Link inertias ``Jz`` are about each link's centre of mass, which sits at
``lg`` from the link's proximal joint.  Chain 1 is the chain whose base is at
(+l0, 0), chain 2 at (-l0, 0).

Counter-masses (seed 001, the balanced RR and 5R, (55)-(72)): ``counter_mass1`` is a
point mass on the proximal link, ``counter_mass2`` one on the distal link, each on the
link's line behind its proximal joint at the distance :meth:`ChainParams.counter_offsets`
gives, so that the chain's gravity terms g# (62)-(63) vanish.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace


@dataclass(frozen=True)
class ChainParams:
    """One RR chain: proximal link 1 (actuated) and distal link 2."""

    l1: float
    l2: float
    lg1: float
    lg2: float
    m1: float
    m2: float
    Jz1: float
    Jz2: float
    J_rotor: float = 0.0
    counter_mass1: float = 0.0
    counter_mass2: float = 0.0

    def counter_offsets(self) -> tuple[float, float]:
        """(L1, L2): where the counter-masses sit [m], along each link from its proximal joint.

        Seed 001 (62)-(63) for an RR chain carrying point masses M1 at L1 on link 1 and M2 at
        L2 on link 2 (from the base joint and from the elbow)::

            g1# = g (M1 L1 + m1 lg1 + (M2 + m2) l1) c1 + g (M2 L2 + m2 lg2) c12
            g2# = g (M2 L2 + m2 lg2) c12

        Both vanish for every pose when (64), with its typo corrected (the seed prints
        ``m2 l2`` where (62) gives ``m2 l1``)::

            L2 = -m2 lg2 / M2,   L1 = -(m1 lg1 + (M2 + m2) l1) / M1

        i.e. the distal link's centre of mass (counter-mass included) is moved to the elbow and
        the proximal link's (carrying all of link 2 at the elbow) to the base joint.  Both are
        negative: behind the joint.  A counter-mass of 0 kg has no place: its entry is 0.  With
        M1 = 0 and M2 > 0 only g2# and the distal part of g1# vanish; with M2 = 0 and M1 > 0
        only the proximal link's own part of g1#.
        """
        M1, M2 = self.counter_mass1, self.counter_mass2
        L2 = -self.m2 * self.lg2 / M2 if M2 > 0.0 else 0.0
        L1 = -(self.m1 * self.lg1 + (M2 + self.m2) * self.l1) / M1 if M1 > 0.0 else 0.0
        return L1, L2


#: A counter-mass may sit at most this many chain lengths (l1 + l2) behind its joint: a
#: lighter one (tiny masses, far away) is refused as non-physical.
COUNTER_REACH = 10.0


@dataclass(frozen=True)
class FiveBarParams:
    """The whole 5R: base half-distance, two chains, end-effector mass, gravity."""

    l0: float
    chain1: ChainParams
    chain2: ChainParams
    m0: float = 0.0
    gravity: tuple = field(default=(0.0, 0.0, 0.0))

    def validate(self) -> "FiveBarParams":
        """Raise ValueError naming the first non-physical parameter."""
        _check("l0", self.l0, positive=True)
        _check("m0", self.m0)
        if len(self.gravity) != 3 or not all(math.isfinite(g) for g in self.gravity):
            raise ValueError(f"gravity must be 3 finite numbers, got {self.gravity!r}")
        for k, chain in ((1, self.chain1), (2, self.chain2)):
            for f in fields(chain):
                value = getattr(chain, f.name)
                positive = f.name in ("l1", "l2")
                _check(f"chain{k}.{f.name}", value, positive=positive)
        if 2.0 * self.l0 >= self.chain1.l1 + self.chain1.l2 + self.chain2.l1 + self.chain2.l2:
            raise ValueError(
                f"links cannot close the loop: base distance 2*l0 = {2 * self.l0:g} m "
                f"exceeds the reach of both chains together"
            )
        self.check_counter_masses()
        counter = max(c.counter_mass1 + c.counter_mass2 for c in (self.chain1, self.chain2))
        if self.m0 > 0.0 and counter > 0.0:
            raise ValueError(
                f"m0 = {self.m0!r} kg with counter-masses (counter_mass1/counter_mass2 > 0): the "
                f"counter-masses balance each chain without an end-effector mass (seed 001 (64)), "
                f"so the pair is refused; set m0 = 0 or both counter-masses to 0"
            )
        return self

    def check_counter_masses(self, name=lambda k, j: f"chain{k}.counter_mass{j}") -> None:
        """Raise ValueError for a counter-mass too light to balance its chain: it would sit more
        than :data:`COUNTER_REACH` chain lengths behind its joint.  The message calls the mass
        of chain k, link j ``name(k, j)`` (an FMU names it by its own variable)."""
        for k, chain in ((1, self.chain1), (2, self.chain2)):
            reach = COUNTER_REACH * (chain.l1 + chain.l2)
            for j, (mass, offset) in enumerate(zip((chain.counter_mass1, chain.counter_mass2),
                                                   chain.counter_offsets()), start=1):
                if abs(offset) > reach:
                    raise ValueError(
                        f"{name(k, j)} = {mass!r} kg is too light to balance chain {k}: it would "
                        f"sit {abs(offset):.3g} m behind its joint, more than {COUNTER_REACH:g} times the "
                        f"chain's length ({reach:.3g} m)"
                    )

    def with_counter_masses(self, counter_mass1: float, counter_mass2: float) -> "FiveBarParams":
        """Both chains with ``counter_mass1`` on the proximal and ``counter_mass2`` on the
        distal link [kg], placed by :meth:`ChainParams.counter_offsets`."""
        return replace(
            self,
            chain1=replace(self.chain1, counter_mass1=float(counter_mass1), counter_mass2=float(counter_mass2)),
            chain2=replace(self.chain2, counter_mass1=float(counter_mass1), counter_mass2=float(counter_mass2)),
        )

    def with_rotors(self, J_rotor1: float, J_rotor2: float) -> "FiveBarParams":
        return replace(
            self,
            chain1=replace(self.chain1, J_rotor=float(J_rotor1)),
            chain2=replace(self.chain2, J_rotor=float(J_rotor2)),
        )


def _check(name: str, value: float, positive: bool = False) -> None:
    if not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    if positive and value <= 0.0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    if value < 0.0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")


def _table3_chain() -> ChainParams:
    """Table 3 (both chains)."""
    return ChainParams(l1=0.120, l2=0.150, lg1=0.060, lg2=0.075, m1=0.143, m2=0.171,
                       Jz1=1.716e-4, Jz2=3.206e-4)


def _bench() -> FiveBarParams:
    """Tables 4 (chain 1) and 5 (chain 2), rotors of Tables 16 and 18."""
    from motor.presets import get_motor_preset

    chain1 = ChainParams(l1=0.120, l2=0.160, lg1=0.060, lg2=0.078, m1=0.062, m2=0.124,
                         Jz1=1.073e-4, Jz2=4.380e-4)
    chain2 = ChainParams(l1=0.120, l2=0.160, lg1=0.060, lg2=0.058, m1=0.062, m2=0.097,
                         Jz1=2.960e-4, Jz2=9.800e-4)
    return FiveBarParams(l0=0.050, chain1=chain1, chain2=chain2, m0=0.0).with_rotors(
        get_motor_preset("motor1").J_rotor, get_motor_preset("motor2").J_rotor
    )


PRESET_NAMES = ("thesis_sim", "bench")


def get_preset(name: str) -> FiveBarParams:
    """The named preset.

    Raises
    ------
    ValueError
        For an unknown name, listing the valid ones.
    """
    if name == "thesis_sim":
        return FiveBarParams(l0=0.050, chain1=_table3_chain(), chain2=_table3_chain(), m0=0.0)
    if name == "bench":
        return _bench()
    raise ValueError(f"preset: unknown preset {name!r}; valid: {', '.join(PRESET_NAMES)}")
