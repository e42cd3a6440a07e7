"""Current observer: static (7.20) and dynamic (exact ZOH of 4.163)."""

import math

import numpy as np
import pytest

from motor import CurrentObserver, Drive, motor1, motor2

T = 1e-3


def test_static_observer_is_7_20():
    """Catches a static observer that is not (7.20) or that keeps memory between calls."""
    obs = CurrentObserver(motor1)
    assert obs.estimate(6.0, 40.0, T) == pytest.approx((6.0 - motor1.ke * 40.0) / motor1.R, rel=1e-15)
    assert obs.estimate(6.0, 40.0, T) == obs.estimate(6.0, 40.0, 5 * T)  # memoryless


@pytest.mark.parametrize("params", [motor1, motor2])
def test_dynamic_observer_reproduces_drive_current(params):
    """Same parameters, same held inputs: the dynamic estimate equals the drive's current."""
    rng = np.random.default_rng(1)
    drive, obs = Drive(params, mode="voltage"), CurrentObserver(params, "dynamic")
    omega = 0.0
    obs.reset(0.0, omega0=omega)          # the speed held over the first step
    for _ in range(200):
        omega_next = omega + rng.normal(0.0, 2.0)
        _, v, i = drive.step(0.0, rng.uniform(-30, 30), omega, 0.0, T)
        assert obs.estimate(v, omega_next, T) == pytest.approx(i, rel=1e-12, abs=1e-12)
        omega = omega_next


def test_static_observer_lags_true_current_by_electrical_transient():
    """After a voltage step the static estimate jumps to v/R while i rises with L/R."""
    drive, obs = Drive(motor1, mode="voltage"), CurrentObserver(motor1)
    _, v, i = drive.step(0.0, 10.0, 0.0, 0.0, T)
    i_hat = obs.estimate(v, 0.0, T)
    assert i_hat == pytest.approx(10.0 / motor1.R)
    assert i == pytest.approx(i_hat * (1 - math.exp(-motor1.R * T / motor1.L)), rel=1e-12)


@pytest.mark.parametrize("name", ["v", "omega", "h"])
def test_bad_observer_input_named(name):
    """Catches an observer that accepts NaN or an unknown kind, or names the wrong input in its refusal."""
    args = {"v": 1.0, "omega": 0.0, "h": T}
    args[name] = math.nan
    with pytest.raises(ValueError, match=rf"^{name} must be a finite number, got nan"):
        CurrentObserver(motor2, "dynamic").estimate(**args)
    with pytest.raises(ValueError, match="kind must be one of 'static', 'dynamic'; got 'kalman'"):
        CurrentObserver(motor2, "kalman")


@pytest.mark.parametrize("params", [motor1, motor2])
def test_a_new_or_reset_observer_starts_from_zero_current(params):
    """Catches an observer whose default estimate (constructor, ``reset()``) is not 0 A: a fresh
    dynamic observer must reproduce a fresh drive's current (from rest, 0 A) from the first
    step, and ``reset()`` after use must give back exactly the fresh observer's estimates."""
    rng = np.random.default_rng(7)
    inputs = [(rng.uniform(-30, 30), rng.normal(0.0, 3.0)) for _ in range(20)]
    drive, fresh = Drive(params, mode="voltage"), CurrentObserver(params, "dynamic")
    used = CurrentObserver(params, "dynamic")
    assert fresh.i_hat == 0.0
    for v_ref, _ in inputs:
        used.estimate(v_ref, 5.0, T)
    used.reset()
    assert used.i_hat == 0.0
    for v_ref, _ in inputs:
        _, v, i = drive.step(0.0, v_ref, 0.0, 0.0, T)       # at standstill: the estimate is the current
        estimate = fresh.estimate(v, 0.0, T)
        assert estimate == pytest.approx(i, rel=1e-12, abs=1e-12)
        assert used.estimate(v, 0.0, T) == estimate
