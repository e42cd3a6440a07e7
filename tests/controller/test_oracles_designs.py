"""Designs and sampled components at a second sample time (T = 2 ms), each held against a
computation that shares no code with the product (issue 31, patterns 1 and 2):

- the balance controller's LQR gain and observer gain against a finite-difference
  linearisation of the simulated pendulum (its C derivative), seed 000's drive model (22)
  written here, a ZOH by the matrix exponential and scipy's discrete Riccati solver (the
  product uses python-control's c2d, dlqr and dlqe on the analytic linearisation);
- the current observer (both kinds) against (7.20) and (4.163) solved in closed form;
- the derivator against scipy.signal's own digital Bessel design (``bessel(..., fs=)``,
  prewarped bilinear) run by ``sosfilt`` on backward differences;
- the position law's sliding integral and adaptive gain at T = 2 ms in closed form.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal
from scipy.linalg import expm, solve_discrete_are

from controller import balance
from controller.derivators import Derivator
from controller.position import PositionController
from controller.strategies import get_strategy
from motor import CurrentObserver, get_motor_preset, motor1, motor2
from plant import fivebar, get_preset
from plant.wheeled import SEED, WheeledPendulum

T = 2e-3
#: The pendulum's state entries the design keeps, in the 8-word simulated state
#: (theta, psi, phi, x, y, dtheta, dpsi, dphi): the positions then the rates, x and y left out.
SIMULATED = [0, 1, 2, 5, 6, 7]


def linearised_pendulum(eps=1e-6):
    """(A, B, b_d) of the simulated pendulum at the upright at rest by central differences of
    its derivative (C kernel), inputs (tau_l, tau_r), b_d the body torque's column."""
    plant = WheeledPendulum(SEED)
    rest = np.zeros(8)

    def f(x, u):
        y = rest.copy()
        y[SIMULATED] = x
        return plant.derivative(y, *u)[SIMULATED]

    x0, u0 = np.zeros(6), np.zeros(3)
    A = np.column_stack([(f(x0 + eps * e, u0[:2]) - f(x0 - eps * e, u0[:2])) / (2 * eps) for e in np.eye(6)])
    B3 = np.column_stack([(f(x0, (u0 + eps * e)) - f(x0, (u0 - eps * e))) / (2 * eps) for e in np.eye(3)])
    return A, B3[:, :2], B3[:, 2]


def zoh(A, B, h):
    """(Ad, Bd) of x' = A x + B u with u held over h: the exponential of [[A, B], [0, 0]] h."""
    n, m = B.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n], block[:n, n:] = A, B
    e = expm(block * h)
    return e[:n, :n], e[:n, n:]


def independent_balance_design(yaw):
    """(design, Ad, Bd, K, S, C, V) at T: the product's design, and the ZOH model, the LQR
    gain, the observer's prior covariance S (dual DARE), C and the measurement noise V
    computed here from the pendulum linearised by finite differences and the drives of seed
    000 (22): tau_j = (kt/R) v_j - (kt ke/R + b) omega_j, omega_j the wheel's speed relative
    to the body; Bryson's Q and R; the voltage and body-torque process noise, the encoder
    (quantisation) and gyro measurement noise."""
    settings = balance.BalanceSettings(T=T, yaw=yaw)
    design = balance.design_balance(settings)
    motor = get_motor_preset(settings.motor_preset)
    A, B, b_d = linearised_pendulum()
    half = SEED.W / (2.0 * SEED.R)
    speeds = np.array([[0, 0, 0, 1.0, -1.0, -half], [0, 0, 0, 1.0, -1.0, half]])
    c = motor.kt * motor.ke / motor.R + motor.b
    A_v, B_v = A - c * B @ speeds, motor.kt / motor.R * B
    keep = [0, 1, 2, 3, 4, 5] if yaw else [0, 1, 3, 4]
    assert list(design.states) == keep
    Ad, Bd = zoh(A_v[np.ix_(keep, keep)], B_v[keep], T)
    Q = np.diag([1.0 / balance.STATE_SCALE[i] ** 2 for i in keep])
    R = np.eye(2) / balance.VOLTAGE_SCALE ** 2
    P = solve_discrete_are(Ad, Bd, Q, R)
    K = np.linalg.solve(R + Bd.T @ P @ Bd, Bd.T @ P @ Ad)
    count = 2.0 * math.pi / settings.encoder_counts
    C = np.array([[1.0, -1.0, 0, 0, 0, 0], [0, 0, 0, 0, 1.0, 0]] + ([[0, 0, 1.0, 0, 0, 0]] if yaw else []))[:, keep]
    noise = [count ** 2 / 24.0, balance.GYRO_NOISE ** 2] + ([(SEED.R / SEED.W) ** 2 * count ** 2 / 6.0] if yaw else [])
    G = np.column_stack([Bd, T * b_d[keep]])
    W = G @ np.diag([balance.VOLTAGE_NOISE ** 2] * 2 + [balance.BODY_TORQUE_NOISE ** 2]) @ G.T
    V = np.diag(noise)
    S = solve_discrete_are(Ad.T, C.T, W, V)
    return design, Ad, Bd, K, S, C, V


@pytest.mark.parametrize("yaw", [True, False])
def test_balance_model_and_lqr_gain_are_the_simulated_models_at_2ms(yaw):
    """Ad, Bd: the ZOH of the finite-difference linearisation; K = (R + Bd' P Bd)^-1 Bd' P Ad
    with P scipy's DARE solution (the product: python-control's c2d and dlqr of the analytic
    linearisation)."""
    design, Ad, Bd, K, _, C, _ = independent_balance_design(yaw)
    assert np.allclose(design.Ad, Ad, rtol=1e-6, atol=1e-9) and np.allclose(design.Bd, Bd, rtol=1e-6, atol=1e-12)
    assert np.allclose(design.K, K, rtol=1e-4, atol=1e-6 * np.abs(K).max())
    assert np.array_equal(design.C, C)


@pytest.mark.parametrize("yaw", [True, False])
def test_balance_observer_corrects_with_the_kalman_filter_gain(yaw):
    """The sample corrects first (x += Lo (y - C x)), then predicts with Ad: the steady-state
    Kalman filter's gain there is M = S C' (C S C' + V)^-1 with S the prior covariance of the
    dual DARE (scipy), not the predictor's Ad M that python-control's dlqe returns (the design
    used that until issue 31's campaign found it)."""
    design, Ad, _, _, S, C, V = independent_balance_design(yaw)
    filter_gain = S @ C.T @ np.linalg.inv(C @ S @ C.T + V)
    assert np.allclose(design.Lo, filter_gain, rtol=1e-4, atol=1e-6 * np.abs(filter_gain).max())
    assert not np.allclose(design.Lo, Ad @ filter_gain, rtol=1e-4, atol=1e-6 * np.abs(filter_gain).max())


@pytest.mark.parametrize("params", [motor1, motor2], ids=["motor1", "motor2"])
def test_observers_at_2ms_are_7_20_and_4_163_in_closed_form(params):
    """Static: i_hat = (v - ke omega) / R, omega the present speed.  Dynamic: the current of
    L di/dt = v - R i - ke omega_prev over h = 2 ms from the last estimate, exactly."""
    static, dynamic = CurrentObserver(params, "static"), CurrentObserver(params, "dynamic")
    i_hat, omega_prev = 0.3, 4.0
    static.reset(0.3, omega_prev)
    dynamic.reset(0.3, omega_prev)
    a = math.exp(-params.R * T / params.L)
    for k in range(12):
        v, omega = 5.0 * math.sin(0.7 * k) + 1.0, 4.0 + 3.0 * math.cos(0.4 * k)
        assert static.estimate(v, omega, T) == pytest.approx((v - params.ke * omega) / params.R, rel=1e-12)
        i_hat = a * i_hat + (1.0 - a) * (v - params.ke * omega_prev) / params.R
        assert dynamic.estimate(v, omega, T) == pytest.approx(i_hat, rel=1e-10, abs=1e-13)
        omega_prev = omega


@pytest.mark.parametrize("fc_vel, fc_acc", [(100.0, 40.0), (60.0, 25.0)])
def test_derivator_at_2ms_is_scipys_bessel_filters_on_backward_differences(fc_vel, fc_acc):
    """dq = F_v(z) (q_k - q_k-1)/T and ddq = F_a(z) (dq'_k - dq'_k-1)/T with dq' the velocity
    filter's output, F_v, F_a scipy's digital Bessel low-passes (orders 2 and 8, -3 dB at
    fc, design at fs = 1/T), from rest at q0, two channels."""
    derivator = Derivator(fc_vel, fc_acc, T)
    q0 = np.array([0.2, -0.5])
    derivator.reset(q0)
    t = np.arange(300) * T
    q = np.column_stack([0.2 + 0.3 * np.sin(2 * np.pi * 3.0 * t) + 2.0 * t ** 2, -0.5 + 0.1 * t])
    got = np.array([np.concatenate(derivator.step(row)) for row in q])
    sos_v = signal.bessel(2, fc_vel, norm="mag", fs=1.0 / T, output="sos")
    sos_a = signal.bessel(8, fc_acc, norm="mag", fs=1.0 / T, output="sos")
    difference = np.diff(np.vstack([q0, q]), axis=0) / T
    velocity = signal.sosfilt(sos_v, difference, axis=0)
    acceleration = signal.sosfilt(sos_a, np.diff(np.vstack([np.zeros(2), velocity]), axis=0) / T, axis=0)
    scale_v, scale_a = np.abs(velocity).max(), np.abs(acceleration).max()
    assert np.allclose(got[:, :2], velocity, rtol=1e-9, atol=1e-9 * scale_v)
    assert np.allclose(got[:, 2:], acceleration, rtol=1e-8, atol=1e-8 * scale_a)


def test_the_sliding_integral_and_adaptive_gain_use_the_controllers_own_period():
    """PositionController(T = 2 ms), stepped without dt: a constant error at rest gives
    s = kp e, k grows by gamma a sample from the second on (6.66) and the integral (6.65)
    after N samples is T sign(s) (N k0 + gamma N (N - 1) / 2), with T = 2 ms."""
    k0, gamma, N = 50.0, 4.0, 30
    st = get_strategy("PDMDq").with_(k=(k0, k0), gamma=(gamma, gamma), phi=1.0)
    bench = get_preset("bench")
    ctrl = PositionController(bench, st, T=T)
    x, y = 0.0, 0.15
    q = fivebar.inverse_kinematics(bench, x, y)
    measured = (q[0] - 0.01, q[2] + 0.02)
    for n in range(N):
        ctrl.step(n * T, *measured, 0, 0, 0, 0, x, y, 0, 0, 0, 0)
    s = np.array(ctrl.s)
    closed = T * np.sign(s) * (N * k0 + gamma * N * (N - 1) / 2)
    assert np.allclose(ctrl.integral, closed, rtol=1e-12)
    assert np.allclose(ctrl.k, k0 + gamma * (N - 1), rtol=1e-12)
