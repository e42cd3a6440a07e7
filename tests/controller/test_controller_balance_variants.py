"""The balance design (controller/balance.py) with its settings away from the defaults:
ideal drives, no motor friction, another encoder, another sample time, another pendulum,
against a design computed here (finite-difference linearisation of that pendulum's C model,
ZOH by expm, scipy's DARE for the LQR gain and the Kalman filter gain)."""
import math

import numpy as np
import pytest
from scipy.linalg import expm, solve_discrete_are

from controller import balance
from motor import get_motor_preset
from plant.wheeled import SEED, WheeledPendulum

SIMULATED = [0, 1, 2, 5, 6, 7]          # theta, psi, phi, dtheta, dpsi, dphi in the 8-word state
OTHER = SEED.with_(M=0.8, H=0.2, L=0.1, J_psi=0.8 * 0.1 ** 2 / 3.0, W=0.18, R=0.05, J_w=0.03 * 0.05 ** 2 / 2.0)


def linearised(params, eps=1e-6):
    """(A, B, b_d) at the upright at rest by central differences of the C derivative."""
    plant, rest = WheeledPendulum(params), np.zeros(8)

    def f(x, u):
        y = rest.copy()
        y[SIMULATED] = x
        return plant.derivative(y, *u)[SIMULATED]

    A = np.column_stack([(f(e * eps, np.zeros(3)) - f(-e * eps, np.zeros(3))) / (2 * eps) for e in np.eye(6)])
    B3 = np.column_stack([(f(np.zeros(6), e * eps) - f(np.zeros(6), -e * eps)) / (2 * eps) for e in np.eye(3)])
    return A, B3[:, :2], B3[:, 2]


def independent(settings, params):
    """(Ad, Bd, K, C, filter gain) for ``settings`` on ``params``, computed here."""
    motor = get_motor_preset(settings.motor_preset)
    A, B, b_d = linearised(params)
    half = params.W / (2.0 * params.R)
    speeds = np.array([[0, 0, 0, 1.0, -1.0, -half], [0, 0, 0, 1.0, -1.0, half]])   # wheel speeds on the body
    c = (motor.kt * motor.ke / motor.R if settings.electrics == "quasi_static" else 0.0) + \
        (motor.b if settings.friction else 0.0)
    A_v, B_v = A - c * B @ speeds, motor.kt / motor.R * B
    keep = [0, 1, 2, 3, 4, 5] if settings.yaw else [0, 1, 3, 4]
    n = len(keep)
    block = np.zeros((n + 2, n + 2))
    block[:n, :n], block[:n, n:] = A_v[np.ix_(keep, keep)], B_v[keep]
    e = expm(block * settings.T)
    Ad, Bd = e[:n, :n], e[:n, n:]
    Q = np.diag([1.0 / balance.STATE_SCALE[i] ** 2 for i in keep])
    R = np.eye(2) / balance.VOLTAGE_SCALE ** 2
    P = solve_discrete_are(Ad, Bd, Q, R)
    K = np.linalg.solve(R + Bd.T @ P @ Bd, Bd.T @ P @ Ad)
    count = 2.0 * math.pi / settings.encoder_counts
    rows = [[1.0, -1.0, 0, 0, 0, 0], [0, 0, 0, 0, 1.0, 0]] + ([[0, 0, 1.0, 0, 0, 0]] if settings.yaw else [])
    C = np.array(rows)[:, keep]
    V = np.diag([count ** 2 / 24.0, balance.GYRO_NOISE ** 2] +
                ([(params.R / params.W) ** 2 * count ** 2 / 6.0] if settings.yaw else []))
    G = np.column_stack([Bd, settings.T * b_d[keep]])
    W = G @ np.diag([balance.VOLTAGE_NOISE ** 2] * 2 + [balance.BODY_TORQUE_NOISE ** 2]) @ G.T
    S = solve_discrete_are(Ad.T, C.T, W, V)
    return Ad, Bd, K, C, S @ C.T @ np.linalg.inv(C @ S @ C.T + V)


@pytest.mark.parametrize("settings, params", [
    (balance.BalanceSettings(T=5e-3, electrics="ideal", friction=True, encoder_counts=1024), SEED),
    (balance.BalanceSettings(T=1e-3, electrics="quasi_static", friction=False, yaw=False, encoder_counts=512), OTHER),
    (balance.BalanceSettings(T=4e-3, electrics="ideal", friction=False, encoder_counts=2000), OTHER),
    (balance.BalanceSettings(T=2e-3, encoder_counts=8192), OTHER),
], ids=["ideal-5ms-1024", "nofriction-noyaw-other", "ideal-nofriction-other", "2ms-8192-other"])
def test_the_design_for_other_settings_is_the_one_computed_here(settings, params):
    """Catches a design that ignores a setting or the pendulum given: the back-EMF kept with
    ideal drives, the motor's b kept without friction, the encoder's resolution or the sample
    time of the defaults, the default pendulum's linearisation, body-torque column or
    wheel geometry."""
    design = balance.design_balance(settings, OTHER if params is OTHER else None)
    Ad, Bd, K, C, Lo = independent(settings, params)
    assert np.allclose(design.Ad, Ad, rtol=1e-6, atol=1e-9) and np.allclose(design.Bd, Bd, rtol=1e-6, atol=1e-12)
    assert np.allclose(design.K, K, rtol=1e-4, atol=1e-6 * np.abs(K).max())
    assert np.array_equal(design.C, C)
    assert np.allclose(design.Lo, Lo, rtol=1e-4, atol=1e-6 * np.abs(Lo).max())
    assert design.settings == settings


@pytest.mark.parametrize("change, message", [
    (dict(T=5e-6), "parameter T = 5e-06 s must be in [1e-05, 1] s"),
    (dict(T=1.5), "parameter T = 1.5 s must be in [1e-05, 1] s"),
    (dict(v_battery=0.0), "parameter v_battery = 0.0 V must be > 0"),
    (dict(v_battery=math.nan), "parameter v_battery = nan V must be > 0"),
    (dict(electrics="full"), "parameter electrics = 'full'; valid: quasi_static, ideal"),
    (dict(encoder_counts=0), "parameter encoder_counts = 0 must be a positive integer"),
    (dict(encoder_counts=4096.0), "parameter encoder_counts = 4096.0 must be a positive integer"),
])
def test_each_bad_setting_is_refused_naming_it(change, message):
    """Catches a setting left unchecked or refused with another's name or without its value."""
    with pytest.raises(ValueError) as caught:
        balance.design_balance(balance.BalanceSettings(**change))
    assert str(caught.value) == message
    assert balance.BalanceSettings(T=1e-5).validate() and balance.BalanceSettings(T=1.0).validate()
