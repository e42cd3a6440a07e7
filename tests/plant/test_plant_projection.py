"""PlantSimulator's projection (Newton on the loop residual 5.18 with x, y fixed, then
dq = C dq#) on both kernels: the general algorithm's (plant/parallel.py) and the C kernel's
(pc_fivebar_project) give the same state, a run with projection on either kernel is the same
run, and the projected state is on the constraint manifold with x, y and their rates kept."""
from __future__ import annotations

import math

import numpy as np
import pytest

from plant import IntegratorSettings, PlantSimulator, fast5r, get_preset
from plant.parallel import mechanism_state


def off_manifold_state(sim):
    """The simulator's state moved off the manifold: every angle and rate disturbed."""
    rng = np.random.default_rng(7)
    y = sim.y.copy()
    y[3:7] += rng.normal(scale=2e-3, size=4)
    y[7:9] = 0.05, -0.04
    y[10:14] += rng.normal(scale=0.1, size=4)
    return y


@pytest.mark.parametrize("kernel", ["general", "fast"])
def test_the_projection_closes_the_loop_and_keeps_the_platform_and_its_rates(kernel):
    """Catches a projection that moves x, y or their rates, leaves the loop open, runs the other
    kernel's code (or none), or differs between the kernels beyond rounding."""
    sim = PlantSimulator(get_preset("thesis_sim"), 0.02, 0.16, IntegratorSettings(kernel=kernel, project=True))
    y = off_manifold_state(sim)
    projected = sim.project(y)
    assert np.array_equal(projected[[0, 1, 7, 8]], y[[0, 1, 7, 8]])
    st = mechanism_state(sim.mechanism, projected[:7], projected[7:])
    assert np.linalg.norm(st.residual) < 1e-12
    assert np.linalg.norm(st.A @ projected[7:]) < 1e-12 * np.linalg.norm(projected[7:])   # velocity constraints
    assert not np.allclose(projected, y, atol=1e-6)                                        # it had work to do
    c_kernel = fast5r.project(fast5r.pack_params(get_preset("thesis_sim")), y, 3)
    if kernel == "fast":
        assert np.array_equal(projected, c_kernel)
    else:
        np.testing.assert_allclose(projected, c_kernel, rtol=1e-12, atol=1e-14)


def test_a_projected_run_is_the_same_on_both_kernels():
    """Catches the projection switched on one kernel only, or stepping from the unprojected state."""
    runs = {k: PlantSimulator(get_preset("thesis_sim"), 0.0, 0.17, IntegratorSettings(kernel=k, project=True))
            for k in ("general", "fast")}
    for k in range(100):
        t = k * 1e-3
        for sim in runs.values():
            sim.step(0.05 * math.sin(7 * t), 0.05 * math.cos(5 * t), 1e-3)
    general, fast = runs["general"].y, runs["fast"].y
    np.testing.assert_allclose(general, fast, rtol=1e-9, atol=1e-12)
    assert runs["general"].residual_norm() < 1e-13 and runs["fast"].residual_norm() < 1e-13
