"""The 5R's parameters (plant/presets.py): what ``with_*`` sets is read back exactly on both
chains, the counter-masses' places zero the chain's weight moments (seed 001 (62)-(64),
written out here), and every non-physical value is refused naming its field and value."""
import math
from dataclasses import fields, replace

import pytest

from plant import get_preset
from plant.presets import ChainParams, FiveBarParams

BENCH = get_preset("bench")


def test_with_counter_masses_and_rotors_set_both_chains_and_nothing_else():
    """Catches a ``with_*`` that sets one chain only, swaps the proximal and distal values,
    drops a value (0 in its place) or changes another field (fast: the balanced plant's own
    tests are slow)."""
    p = BENCH.with_counter_masses(0.3, 1).with_rotors(2e-5, 3)
    for before, after in ((BENCH.chain1, p.chain1), (BENCH.chain2, p.chain2)):
        assert (after.counter_mass1, after.counter_mass2) == (0.3, 1.0)
        assert type(after.counter_mass2) is float and type(p.chain2.J_rotor) is float
        changed = {f.name for f in fields(ChainParams) if getattr(after, f.name) != getattr(before, f.name)}
        assert changed == {"counter_mass1", "counter_mass2", "J_rotor"}
    assert (p.chain1.J_rotor, p.chain2.J_rotor) == (2e-5, 3.0)
    assert (p.l0, p.m0, p.gravity) == (BENCH.l0, BENCH.m0, BENCH.gravity)


@pytest.mark.parametrize("M1, M2", [(0.4, 0.2), (0.4, 0.0), (0.0, 0.2)])
def test_the_counter_offsets_zero_the_weight_moments_they_can(M1, M2):
    """(62)-(63): g2# ~ M2 L2 + m2 lg2 and the proximal part of g1# ~ M1 L1 + m1 lg1 + (M2 + m2) l1
    vanish for the mass that is there; a mass of 0 kg has offset 0.  Catches a wrong term or
    sign in (64) or an offset for an absent mass."""
    for chain in (BENCH.chain1, BENCH.chain2):
        c = replace(chain, counter_mass1=M1, counter_mass2=M2)
        L1, L2 = c.counter_offsets()
        if M2 > 0:
            assert M2 * L2 + c.m2 * c.lg2 == pytest.approx(0.0, abs=1e-16) and L2 < 0
        else:
            assert L2 == 0.0
        if M1 > 0:
            assert M1 * L1 + c.m1 * c.lg1 + (M2 + c.m2) * c.l1 == pytest.approx(0.0, abs=1e-16) and L1 < 0
        else:
            assert L1 == 0.0


CHAIN_FIELDS = [f.name for f in fields(ChainParams)]


@pytest.mark.parametrize("k", [1, 2])
@pytest.mark.parametrize("name", CHAIN_FIELDS)
def test_every_chain_field_is_refused_naming_itself_and_its_value(k, name):
    """Catches a field left out of the check, the wrong chain named, or a length allowed to be 0."""
    chain = getattr(BENCH, f"chain{k}")
    lengths = name in ("l1", "l2")
    cases = [(-0.5, rf"chain{k}\.{name} must be >= 0, got -0\.5"), (math.nan, rf"chain{k}\.{name} must be a "
                                                                               rf"finite number, got nan"),
             ("0.1", rf"chain{k}\.{name} must be a finite number, got '0\.1'")]
    if lengths:
        cases[0] = (0.0, rf"chain{k}\.{name} must be > 0, got 0\.0")
    for value, message in cases:
        bad = replace(BENCH, **{f"chain{k}": replace(chain, **{name: value})})
        with pytest.raises(ValueError, match=f"^{message}$"):
            bad.validate()


def test_the_whole_mechanism_is_refused_naming_what_is_wrong():
    """Catches l0, m0 or gravity unchecked, and a loop closing check that accepts bases exactly as
    far apart as the four links are long (a single, stretched pose: >=, not >)."""
    for change, message in [(dict(l0=0.0), r"^l0 must be > 0, got 0\.0$"), (dict(m0=-1.0), r"^m0 must be >= 0, got -1\.0$"),
                            (dict(gravity=(0.0, -9.81)), r"^gravity must be 3 finite numbers, got \(0\.0, -9\.81\)$"),
                            (dict(gravity=(0.0, math.inf, 0.0)), r"^gravity must be 3 finite numbers")]:
        with pytest.raises(ValueError, match=message):
            replace(BENCH, **change).validate()
    chain = ChainParams(l1=0.25, l2=0.5, lg1=0.125, lg2=0.25, m1=0.1, m2=0.1, Jz1=1e-4, Jz2=1e-4)
    FiveBarParams(l0=0.75 - 2.0 ** -20, chain1=chain, chain2=chain).validate()
    with pytest.raises(ValueError, match=r"^links cannot close the loop: base distance 2\*l0 = 1\.5 m exceeds"):
        FiveBarParams(l0=0.75, chain1=chain, chain2=chain).validate()


def test_an_end_effector_mass_with_counter_masses_is_refused_naming_both():
    """Catches the pair accepted when only one chain or only the distal link carries a counter-mass."""
    one = replace(BENCH, m0=0.05, chain2=replace(BENCH.chain2, counter_mass2=0.2))
    with pytest.raises(ValueError, match=r"^m0 = 0\.05 kg with counter-masses"):
        one.validate()
    replace(BENCH, m0=0.05).validate()


@pytest.mark.parametrize("k", [1, 2])
@pytest.mark.parametrize("j", [1, 2])
def test_a_counter_mass_is_refused_only_beyond_ten_chain_lengths_word_for_word(k, j):
    """The lightest counter-mass of each link of each chain: the mass that puts it 0.99 of 10
    chain lengths (l1 + l2) behind its joint is accepted, the one for 1.01 of it refused word
    for word with the distance and the limit (the offsets of counter_offsets' docstring,
    L2 = -m2 lg2 / M2, L1 = -(m1 lg1 + m2 l1) / M1 with M2 = 0, solved for the mass here).
    Catches the reach without l2 (or l1), the comparison reversed, another chain's length, and
    a message naming another mass or chain."""
    params = get_preset("bench")
    chain = getattr(params, f"chain{k}")
    reach = 10.0 * (chain.l1 + chain.l2)
    moment = chain.m2 * chain.lg2 if j == 2 else chain.m1 * chain.lg1 + chain.m2 * chain.l1
    assert params.m0 == 0.0 and chain.l2 > 0.2 * chain.l1 and moment > 0.0

    def with_mass(distance):
        mass = moment / distance
        return mass, replace(params, **{f"chain{k}": replace(chain, **{f"counter_mass{j}": mass})})

    _, near = with_mass(0.99 * reach)
    assert near.validate() is near and abs(getattr(near, f"chain{k}").counter_offsets()[j - 1]) > 10.0 * chain.l1
    far_mass, far = with_mass(1.01 * reach)
    with pytest.raises(ValueError) as caught:
        far.validate()
    assert str(caught.value) == (f"chain{k}.counter_mass{j} = {far_mass!r} kg is too light to balance chain {k}: "
                                 f"it would sit {1.01 * reach:.3g} m behind its joint, more than 10 times the "
                                 f"chain's length ({reach:.3g} m)")
