"""Seed 001's sliding-mode law (section 1.2; strategies SMCq, SMCx): its closed loop against
the analytic sliding dynamics, and its relation to computed torque (docs/controller.md).

The law is the C kernel (kernels/src/law.c); the exact model's terms come from the 5R kernel
(``kernel="fast"``) or the general algorithm (``kernel="general"``)."""
import math

import numpy as np
import pytest

from controller.position import PositionController
from controller.strategies import get_strategy
from controller.trajectories import circle
from plant import IntegratorSettings, PlantSimulator, fivebar, get_preset

BENCH = get_preset("bench")


def analytic_s(s0, k, phi, t):
    """ds/dt = -k sat(s/phi): a ramp of slope -k sign(s0) until |s| = phi, then s = ±phi exp(-k/phi t')."""
    t = np.asarray(t)
    reach = max(abs(s0) - phi, 0.0) / k
    inside = math.copysign(min(abs(s0), phi), s0)
    return np.where(t < reach, s0 - math.copysign(k, s0) * t, inside * np.exp(-(k / phi) * (t - reach)))


KERNELS = ("fast", "general")


def sliding_deviation(name, dt, kernel="fast", duration=0.06):
    """Exact model, ideal actuators (torques held over dt), the bench started 2 mm off the circle:
    the largest deviation of the measured s = de + lam e from :func:`analytic_s`, and max |s|."""
    trajectory = circle()
    sim = PlantSimulator(BENCH, *trajectory.start_point, settings=IntegratorSettings(substeps=4))
    ctrl = PositionController(BENCH, get_strategy(name), model="exact", kernel=kernel)
    st = ctrl.strategy
    measured, times = [], []
    n = int(round(duration / dt))
    for k in range(n + 1):
        t = k * dt
        o = sim.outputs()
        tau1, tau2, _, _ = ctrl.step(t, o["q1"], o["q2"], o["dq1"], o["dq2"], 0.0, 0.0, *trajectory(t))
        measured.append(list(ctrl.s))
        times.append(t)
        if k < n:
            sim.step(tau1, tau2, dt)
    measured = np.array(measured)
    worst, peak = 0.0, 0.0
    for i in (0, 1):
        expected = analytic_s(measured[0, i], st.k[i], st.phi, times)
        worst = max(worst, float(np.abs(measured[:, i] - expected).max()))
        peak = max(peak, float(np.abs(expected).max()))
    return worst, peak, measured


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("name", ["SMCx", "SMCq"])
def test_sliding_variable_reaches_the_layer_at_rate_k_then_decays(name, kernel):
    """With the exact model the law makes ds/dt = -k sat(s/phi) for s = de + lam e; the
    deviation comes from the 1 ms zero-order hold only: O(h), 3-5x smaller at h/4."""
    dev_1ms, peak, measured = sliding_deviation(name, 1e-3, kernel)
    dev_quarter, _, _ = sliding_deviation(name, 2.5e-4, kernel)
    st = get_strategy(name)
    assert np.abs(measured[0]).max() > 1.5 * st.phi      # the start is outside the layer: both phases seen
    assert dev_1ms < 0.1 * peak
    assert 3.0 < dev_1ms / dev_quarter < 5.0


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("space", ["q", "x"])
def test_inside_its_layer_with_k_equal_lam_phi_it_is_computed_torque(space, kernel):
    """Inside |s| < phi the law is u' = H (ddr_d + (lam + k/phi) de + (lam k/phi) e) + h: with
    k = lam phi, kv = 2 lam and kp = lam^2, i.e. TC with the same lam (7.21, k = 0)."""
    tc = get_strategy(f"TC{space}")
    smc = get_strategy(f"SMC{space}").with_(lam=tc.lam, phi=1e6, k=(tc.lam * 1e6, tc.lam * 1e6))
    rng = np.random.default_rng(3)
    for _ in range(20):
        x, y = rng.uniform(-0.04, 0.04), rng.uniform(0.12, 0.2)
        a = fivebar.inverse_kinematics(BENCH, x, y)
        measured = (a[0] + rng.normal(scale=0.01), a[2] + rng.normal(scale=0.01), *rng.normal(size=2), 0.0, 0.0)
        reference = (x, y, *rng.normal(scale=0.2, size=2), *rng.normal(size=2))
        u_tc = PositionController(BENCH, tc, model="exact", kernel=kernel).step(0.0, *measured, *reference)
        u_smc = PositionController(BENCH, smc, model="exact", kernel=kernel).step(0.0, *measured, *reference)
        np.testing.assert_allclose(u_smc, u_tc, rtol=1e-9, atol=1e-12)


def test_seed_law_needs_the_model():
    """Catches seed 001's law accepted without the model, or an unknown law name accepted."""
    with pytest.raises(ValueError, match="seed 001's law needs the model"):
        get_strategy("SMCx").with_(model_based=False)
    with pytest.raises(ValueError, match="law = 'nope' is unknown"):
        get_strategy("SMCx").with_(law="nope")
