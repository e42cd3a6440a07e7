"""plant/spec.py: what a link, a chain and a platform are when their optional keys are
left out (docs/spec.md): DH parameters 0, revolute, a link with no mass, centre of mass
or inertia (it adds nothing to the dynamics), no rotor, gear ratio 1, mode 0, a chain at
the origin unrotated, a platform of no mass starting at the origin."""
import math

import numpy as np
import pytest

from plant import spec as plant_spec
from plant.specsim import serial_terms

#: The smallest serial spec: link 1 with a mass at its distal joint (com 0 in B_1), link 2
#: with nothing but its length.
MINIMAL = """gravity = [0.0, -9.81, 0.0]

[[chains]]

[[chains.links]]
name = "q1"
actuated = true
a = 0.1
mass = 0.3

[[chains.links]]
name = "q2"
a = 0.2
"""


def test_a_link_without_mass_keys_adds_nothing_to_the_dynamics():
    """Only link 1's point mass m at the end of a = 0.1 acts: M = [[m a^2, 0], [0, 0]],
    v = 0, g = (m g a cos q1, 0), whatever q2 and the rates."""
    spec = plant_spec.loads(MINIMAL, source="t.toml")
    m, a, g = 0.3, 0.1, 9.81
    for q1, q2, dq1, dq2 in [(0.3, 0.4, 1.0, -2.0), (-1.2, 2.5, 0.5, 3.0), (0.0, -0.7, 0.0, 0.0)]:
        terms = serial_terms(spec, [q1, q2], [dq1, dq2])
        assert np.asarray(terms.M) == pytest.approx(np.array([[m * a * a, 0.0], [0.0, 0.0]]), abs=1e-15)
        assert np.asarray(terms.v) == pytest.approx([0.0, 0.0], abs=1e-15)
        assert np.asarray(terms.g) == pytest.approx([m * g * a * math.cos(q1), 0.0], abs=1e-15)


def test_the_optional_keys_of_links_and_chains_default_as_the_format_says():
    spec = plant_spec.loads(MINIMAL, source="t.toml")
    c = spec.chains[0]
    assert c.base == (0.0, 0.0, 0.0) and c.attach == (0.0, 0.0, 0.0)
    assert np.array_equal(np.asarray(c.rotation), np.eye(3))
    chain = c.chain
    assert [(j.kind, j.alpha, j.d, j.theta) for j in chain.joints] == [("R", 0.0, 0.0, 0.0)] * 2
    assert tuple(chain.rotor_inertia) == (0.0, 0.0) and tuple(chain.gear_ratio) == (1.0, 1.0)
    second = chain.links[1]
    assert second.mass == 0.0 and tuple(second.com) == (0.0, 0.0, 0.0)
    assert np.array_equal(np.asarray(second.inertia), np.zeros((3, 3)))
    assert [(info.mode, info.actuated) for info in c.joints] == [(0.0, True), (0.0, False)]
    assert spec.platform_mass is None


def test_a_platform_without_mass_or_start_has_no_mass_and_starts_at_the_origin():
    text = (plant_spec.SPEC_DIR / "bench_5r.toml").read_text()
    platform = "[platform]\nmass = 0.0\nindependent = [\"x\", \"y\"]\nstart = [0.07, 0.17, 0.0]\n"
    assert platform in text
    spec = plant_spec.loads(text.replace(platform, '[platform]\nindependent = ["x", "y"]\n'), source="b.toml")
    assert spec.platform_mass == 0.0 and tuple(spec.start) == (0.0, 0.0, 0.0)
