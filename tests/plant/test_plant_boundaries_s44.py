"""The plant's range checks hit exactly at their bounds, on both sides (session 44, training
sample 4421's lesson: a strict and a loose comparison differ only at the bound itself).

A counter-mass exactly 10 chain lengths behind its joint (plant/presets.py: refused only
*beyond* COUNTER_REACH), an exact speed measurement exactly 1e-10 off the model's
(plant/correction.py: taken only *beyond* EXACT_TOLERANCE)."""
from __future__ import annotations

import math
from dataclasses import replace

import pytest

from plant import PlantSimulator, fivebar, get_preset
from plant.correction import corrected_state

H = 2e-3


@pytest.mark.parametrize("k", [1, 2])
def test_a_counter_mass_exactly_ten_chain_lengths_behind_its_joint_is_accepted(k):
    """The docstring's limit: "more than COUNTER_REACH chain lengths behind its joint" is
    refused, so exactly 10 (l1 + l2) is accepted; the next lighter mass (a little farther)
    is refused.  The mass is m2 lg2 / reach, moved by ulps until its offset is the reach to
    the bit."""
    params = get_preset("bench")
    chain = getattr(params, f"chain{k}")
    reach = 10.0 * (chain.l1 + chain.l2)

    def placed(mass):
        return replace(params, **{f"chain{k}": replace(chain, counter_mass1=0.0, counter_mass2=mass)})

    mass = chain.m2 * chain.lg2 / reach
    for _ in range(100):
        offset = abs(getattr(placed(mass), f"chain{k}").counter_offsets()[1])
        if offset == reach:
            break
        mass = math.nextafter(mass, math.inf if offset > reach else 0.0)
    assert abs(getattr(placed(mass), f"chain{k}").counter_offsets()[1]) == reach
    assert placed(mass).validate().m0 == 0.0
    lighter = math.nextafter(mass, 0.0)
    assert abs(getattr(placed(lighter), f"chain{k}").counter_offsets()[1]) > reach
    with pytest.raises(ValueError, match=rf"^chain{k}\.counter_mass2 = {lighter!r} kg is too light"):
        placed(lighter).validate()


@pytest.mark.parametrize("name", ["dq1", "dq2"])
def test_an_exact_speed_exactly_1e_10_off_the_models_changes_nothing_and_the_next_number_does(name):
    """At rest the model's speeds are 0 (or -0), so a measured speed of 1e-10 is exactly the
    tolerance away: ignored (the model is within the tolerance); the next number above it is
    taken as it is."""
    sim = PlantSimulator(get_preset("bench"), -0.002, 0.108)
    assert abs(sim.outputs()[name]) == 0.0
    assert corrected_state(sim, {name: 1e-10}, H) is None
    beyond = math.nextafter(1e-10, 1.0)
    z = corrected_state(sim, {name: beyond}, H)
    assert z is not None
    rates = dict(zip(("dq1", "dq2"), fivebar.world_rates(z[7:])))
    assert rates[name] == pytest.approx(beyond, rel=1e-9)
