"""The plant's range checks hit exactly at their bounds, on both sides (session 44, training
sample 4421's lesson: a strict and a loose comparison differ only at the bound itself).

A counter-mass exactly 10 chain lengths behind its joint (plant/presets.py: refused only
*beyond* COUNTER_REACH), an exact speed measurement exactly 1e-10 off the model's
(plant/correction.py: taken only *beyond* EXACT_TOLERANCE), an inertia eigenvalue of exactly
-1e-15 kg m^2 (plant/spec.py: refused only *below* that round-off)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
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


def test_an_inertia_eigenvalue_of_minus_1e_15_is_taken_as_round_off_and_the_next_number_below_refused():
    """plant/spec.py accepts an inertia as positive semi-definite up to a round-off of 1e-15 kg m^2
    in its smallest eigenvalue: principal moments (2e-4, 1e-4, -1e-15) load (the diagonal as
    written), one ulp below -1e-15 is refused naming the key."""
    from plant import spec as plant_spec
    from tests.plant.test_spec import GOOD

    def spec_with(smallest):
        return GOOD.replace("mass = 0.2", f"mass = 0.2\ninertia = [2e-4, 1e-4, {smallest!r}]", 1)

    spec = plant_spec.loads(spec_with(-1e-15), source="t.toml")
    inertia = spec.chains[0].chain.links[1].inertia
    assert np.array_equal(np.asarray(inertia), np.diag([2e-4, 1e-4, -1e-15]))
    below = math.nextafter(-1e-15, -1.0)
    with pytest.raises(plant_spec.SpecError, match=r"chains\[0\]\.links\[1\]\.inertia = .*: must be symmetric "
                                                   r"positive semi-definite \[kg m2\]$"):
        plant_spec.loads(spec_with(below), source="t.toml")
