"""plant/spec.py's inertia check at its rounding tolerance (issue 31, training sweep s44:
compare mutant at spec.py:374, ``eig.min() < -1e-15``).

An inertia must be symmetric positive semi-definite; an eigenvalue down to -1e-15 kg m2 is
taken as rounding (a computed inertia of a flat body), one below it is refused word for word.
"""
from __future__ import annotations

import numpy as np
import pytest

from plant import spec as plant_spec
from tests.plant.test_spec import GOOD


def _with_inertia(values):
    return GOOD.replace("mass = 0.2", f"mass = 0.2\ninertia = [{', '.join(repr(v) for v in values)}]", 1)


def test_an_eigenvalue_of_exactly_minus_1e15_is_taken_as_rounding():
    spec = plant_spec.loads(_with_inertia([1e-3, -1e-15, 0.0]), source="t.toml")
    np.testing.assert_array_equal(np.array(spec.chains[0].chain.links[1].inertia), np.diag([1e-3, -1e-15, 0.0]))


def test_an_eigenvalue_below_minus_1e15_is_refused_naming_the_inertia():
    with pytest.raises(plant_spec.SpecError) as info:
        plant_spec.loads(_with_inertia([1e-3, -2e-15, 0.0]), source="t.toml")
    assert str(info.value) == ("t.toml, line 17: chains[0].links[1].inertia = "
                               f"{np.diag([1e-3, -2e-15, 0.0]).tolist()!r}: must be symmetric positive semi-definite [kg m2]")
