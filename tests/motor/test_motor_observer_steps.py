"""The current observer against the closed form of (4.163) at step lengths other than 1 ms,
from a non-zero start, with the step length changing between calls."""

import math

import numpy as np
import pytest

from motor import CurrentObserver, motor1, motor2


def exact_current(p, i0, v, omega_held, h):
    """i(h) of L di/dt = v - R i - ke omega_held from i0, v and omega_held constant."""
    decay = math.exp(-p.R * h / p.L)
    return i0 * decay + (v - p.ke * omega_held) / p.R * (1.0 - decay)


@pytest.mark.parametrize("params", [motor1, motor2])
def test_the_dynamic_estimate_is_the_closed_form_at_any_step_and_from_any_start(params):
    """Catches a dynamic observer whose coefficients are wrong at a step other than 1 ms, that
    keeps the coefficients of a previous step length, that starts from zero instead of ``i0``,
    that holds the present speed where the previous one was given (``omega0``) or the previous
    where there is none."""
    rng = np.random.default_rng(7)
    obs = CurrentObserver(params, "dynamic")
    obs.reset(0.4, omega0=12.0)
    i, omega_prev = 0.4, 12.0
    for h in (2.5e-4, 3e-3, 3e-3, 1e-3, 2.5e-4, 5e-3):
        v, omega = rng.uniform(-24, 24), rng.uniform(-50, 50)
        i = exact_current(params, i, v, omega_prev, h)
        assert obs.estimate(v, omega, h) == pytest.approx(i, rel=1e-12, abs=1e-12)
        assert obs.i_hat == pytest.approx(i, rel=1e-12, abs=1e-12)
        omega_prev = omega
    obs.reset(-0.3)                          # no previous speed: the present one is held
    assert obs.estimate(5.0, 20.0, 2e-3) == pytest.approx(exact_current(params, -0.3, 5.0, 20.0, 2e-3), rel=1e-12)


@pytest.mark.parametrize("h", [2.5e-4, 4e-3])
def test_the_static_estimate_is_7_20_whatever_the_step_and_the_start(h):
    """Catches a static observer that depends on the step length, on its start ``i0`` or on the
    previous speed (7.20 holds only the present v and omega)."""
    obs = CurrentObserver(motor2, "static")
    obs.reset(3.0, omega0=-40.0)
    for v, omega in ((7.0, 15.0), (-3.0, -60.0)):
        assert obs.estimate(v, omega, h) == pytest.approx((v - motor2.ke * omega) / motor2.R, rel=1e-14)
