"""plant/specsim.py's loop closure ``_close`` at its tolerance exactly (issue 31, training sweep
s44: compare mutants at specsim.py:82 and :88).

A pose whose loop-closure residual is at most the tolerance is closed (returned as it is); one
whose residual exceeds it after Newton is refused (AssemblyError naming the pose and the
residual).  bench_5r's reference pose with its platform moved 0.1 mm does not close, so its
residual r is a tolerance to test at: tol = r takes it, tol one double below r does not (no
Newton iteration allowed, or one).
"""
from __future__ import annotations

import numpy as np
import pytest

import plant.specsim as specsim
from plant import spec as plant_spec
from plant.parallel import mechanism_state


@pytest.fixture(scope="module")
def pose():
    spec = plant_spec.load("bench_5r")
    mech = spec.mechanism
    q = specsim.reference_pose(spec)
    q[0] += 1e-4                      # the platform moved 0.1 mm off its closed pose
    r = float(np.linalg.norm(mechanism_state(mech, q, np.zeros_like(q)).residual))
    assert r > 1e-12    # the premise: the loop is open by more than the floor of the tolerance
    return mech, q, r


@pytest.mark.parametrize("iterations", [0, 1])
def test_a_residual_equal_to_the_tolerance_is_closed_as_it_is(pose, iterations):
    """tol = r: the pose is returned unchanged, before any Newton step (one allowed or none)."""
    mech, q, r = pose
    got = specsim._close(mech, q.copy(), mech.Q_redundant, tol=r, label="test pose", iterations=iterations)
    np.testing.assert_array_equal(got, q)


def test_a_residual_one_double_above_the_tolerance_is_refused_without_newton(pose):
    """tol one double below r and no Newton iteration: refused, naming the pose's label and r."""
    mech, q, r = pose
    with pytest.raises(specsim.AssemblyError, match=rf"^cannot close the loop with the test pose: residual {r:.3g} m "):
        specsim._close(mech, q.copy(), mech.Q_redundant, tol=np.nextafter(r, 0.0), label="test pose", iterations=0)
