"""plant/parallel.py's mechanism_state: M', v', g' of (5.44)-(5.46) are block-diagonal, the
platform's block then each chain's own terms (4.84)-(4.87) at that chain's (q_i, dq_i), with
gravity rotated into the chain's base frame.  Checked on the delta, whose chains are rotated
and carry rotors beyond their first joint and a gear, at non-zero rates: there a rotor's
terms depend on dq, and the chains' q and dq cannot be told apart by a pose at rest.  The
terms are defined at any (q, dq), closed loop or not: the shoulders are tilted (alpha 0.7) so
that a rotor's carrier axes are not parallel to it, where its gyroscopic terms do not vanish."""
from __future__ import annotations

import numpy as np
import pytest

from plant import spec as plant_spec
from plant.parallel import mechanism_state
from plant.serial import chain_dynamics


def _delta_with_rotors_everywhere():
    """delta3 with tilted shoulders and rotors on the elbows (gear 3) and the swings:
    (4.139)-(4.140) for i > 0."""
    text = (plant_spec.SPEC_DIR / "delta3.toml").read_text().replace("mode = 0.6", "mode = 0.6\nalpha = 0.7")
    text = text.replace("mode = 1.6270263453829803", "mode = 1.6270263453829803\nrotor_inertia = 3e-5\ngear_ratio = 3.0")
    text = text.replace("mode = 0.0", "mode = 0.0\nrotor_inertia = 1e-5")
    spec = plant_spec.loads(text, source="delta_rotors.toml")
    assert all(c.chain.rotor_inertia[1] == 3e-5 and c.chain.rotor_inertia[2] == 1e-5 for c in spec.chains)
    return spec


def test_mechanism_terms_are_the_platform_and_each_chains_own_terms_at_its_q_and_dq():
    spec = _delta_with_rotors_everywhere()
    mech = spec.mechanism
    rng = np.random.default_rng(29)
    q = rng.uniform(-1.5, 1.5, 3 + sum(c.chain.dof for c in spec.chains))
    rng = np.random.default_rng(31)
    dq = rng.uniform(-3.0, 3.0, q.size)      # any rates: the terms are defined for all
    st = mechanism_state(mech, q, dq)
    gravity = np.asarray(mech.gravity)
    assert np.linalg.norm(gravity) > 9.0
    np.testing.assert_array_equal(st.M[:3, :3], 0.1 * np.eye(3))
    np.testing.assert_array_equal(st.v[:3], 0.0)
    np.testing.assert_allclose(st.g[:3], -0.1 * gravity, rtol=1e-15)
    start = 3
    for c in spec.chains:
        n = c.chain.dof
        sl = slice(start, start + n)
        own = chain_dynamics(c.chain, q[sl], dq[sl], np.asarray(c.rotation).T @ gravity)
        assert np.abs(own.v).max() > 1e-4        # the rates matter here
        np.testing.assert_allclose(st.M[sl, sl], own.M, rtol=1e-13, atol=1e-16)
        np.testing.assert_allclose(st.v[sl], own.v, rtol=1e-13, atol=1e-16)
        np.testing.assert_allclose(st.g[sl], own.g, rtol=1e-13, atol=1e-16)
        assert not st.M[sl, start + n:].any() and not st.M[start + n:, sl].any()
        start += n
    assert start == q.size


def test_a_rotor_beyond_the_first_joint_changes_the_velocity_terms_with_the_rates():
    """Without rates the rotors add nothing to v'; with them they do (the gyroscopic and
    carried-frame terms of (4.140)), so the rates reach the rotor terms."""
    spec = _delta_with_rotors_everywhere()
    plain = plant_spec.loads(spec.text.replace("rotor_inertia = 3e-5", "rotor_inertia = 0.0").replace(
        "rotor_inertia = 1e-5", "rotor_inertia = 0.0"), source="tilted.toml")
    q = np.linspace(-1.2, 1.3, 12)
    dq = np.linspace(-2.0, 2.5, q.size)
    at_rest = mechanism_state(spec.mechanism, q, np.zeros_like(q)).v
    assert at_rest == pytest.approx(np.zeros_like(q), abs=1e-15)
    moving = mechanism_state(spec.mechanism, q, dq).v - mechanism_state(plain.mechanism, q, dq).v
    assert np.abs(moving).max() > 1e-6
