"""Electrical model (4.162), shaft torque (B.2) and voltage mode of the drive."""

import math

import numpy as np
import pytest

import kernels
from motor import Drive, armature_current_rate, coulomb_friction, electrical_step_coefficients, motor1, motor2

H = 1e-3


def run_voltage(params, v_seq, h=H, method="exact", omega=0.0):
    d = Drive(params, mode="voltage", method=method)
    return np.array([d.step(0.0, v, omega, 0.0, h)[2] for v in v_seq])


@pytest.mark.parametrize("tau_ratio", [0.6067, 0.01])  # L/R over h: thesis motor; 100x shorter
@pytest.mark.parametrize("params", [motor1, motor2])
def test_locked_rotor_voltage_mode_is_analytic(params, tau_ratio):
    """Locked rotor, held voltage: i(t) of (4.162) at every sample to 1e-9 relative."""
    p = params.with_(L=tau_ratio * params.R * H)
    n1, n2, v = 30, 30, 12.0
    i = run_voltage(p, [v] * n1 + [0.0] * n2)
    t = H * np.arange(1, n1 + n2 + 1)
    tau_e = p.L / p.R
    i_on = v / p.R * -np.expm1(-t[:n1] / tau_e)
    i_off = i_on[-1] * np.exp(-(t[n1:] - t[n1 - 1]) / tau_e)
    expected = np.r_[i_on, i_off]
    mask = np.abs(expected) > 1e-250  # 100x-shorter case decays below the double range
    np.testing.assert_allclose(i[mask], expected[mask], rtol=1e-9, atol=0)
    assert np.all(np.abs(i[~mask]) < 1e-250)


def test_voltage_mode_with_speed_and_saturation():
    """Held omega enters through ke omega; commanded voltage is clipped at +-v_max."""
    d = Drive(motor1, mode="voltage")
    tau, v, i = d.step(0.0, 100.0, 50.0, 0.0, H)
    a = math.exp(-motor1.R * H / motor1.L)
    assert v == 24.0
    assert i == pytest.approx((24.0 - motor1.ke * 50.0) / motor1.R * (1 - a), rel=1e-12)
    assert tau == pytest.approx(motor1.kt * i - motor1.b * 50.0 - motor1.mu * math.tanh(100.0), rel=1e-12)
    assert d.step(0.0, -100.0, 0.0, 0.0, H)[1] == -24.0


def test_explicit_euler_unstable_when_step_exceeds_two_time_constants():
    """Documented property: Euler's a = 1 - hR/L; |a| > 1 once h > 2 L/R."""
    fast = motor1.with_(L=0.01 * motor1.R * H)            # L/R 100x shorter than h: a = -99
    a, _ = electrical_step_coefficients(fast.R, fast.L, H, "euler")
    assert a == pytest.approx(-99.0)
    i_euler = run_voltage(fast, [12.0] * 10, method="euler")
    assert abs(i_euler[-1]) > 1e15 and np.all(np.diff(np.sign(i_euler[1:])) != 0)
    np.testing.assert_allclose(run_voltage(fast, [12.0] * 10), 12.0 / fast.R, rtol=1e-12)
    # thesis motor at h = 1 ms (L/R = 0.61 ms): stable but oscillating, a ~ -0.65
    a_nom, _ = electrical_step_coefficients(motor1.R, motor1.L, H, "euler")
    assert -1.0 < a_nom < -0.6
    err = run_voltage(motor1, [12.0] * 40, method="euler") - 12.0 / motor1.R
    assert abs(err[-1]) < 1e-6 and np.all(err[:-1] * err[1:] < 0)


def test_quasi_static_is_steady_state_current():
    """Catches a quasi-static current other than (v - ke omega) / R, or a wrong L = 0 limit of the exact step."""
    i = run_voltage(motor2, [5.0, -3.0], method="quasi_static", omega=20.0)
    np.testing.assert_allclose(i, (np.array([5.0, -3.0]) - motor2.ke * 20.0) / motor2.R, rtol=1e-15)
    assert electrical_step_coefficients(1.0, 0.0, H, "exact") == (0.0, 1.0)  # L = 0 limit


@pytest.mark.parametrize("params", [motor1, motor2])
def test_free_running_motor_settles_at_analytic_speed(params):
    """Ideal inertia J integrated here: omega -> (kt v/R - mu)/(b + kt ke/R) (B.4 at rest)."""
    d = Drive(params, mode="voltage")
    v, omega = 6.5, 0.0
    for _ in range(3000):
        tau, _, _ = d.step(0.0, v, omega, 0.0, H)
        omega += H * tau / params.J_rotor
    w_ss = (params.kt * v / params.R - params.mu) / (params.b + params.kt * params.ke / params.R)
    assert omega == pytest.approx(w_ss, rel=1e-9)
    assert d.torque(omega) == pytest.approx(0.0, abs=1e-12)


def test_coulomb_friction_regularisation():
    """Catches a wrong sign, scale or tanh width of the regularised Coulomb friction, or a non-zero value at rest."""
    assert coulomb_friction(0.0, 0.05, 0.5) == 0.0
    assert coulomb_friction(-2.0, 0.05, 0.5) == pytest.approx(-0.05, rel=1e-3)
    assert coulomb_friction(0.1, 0.05, 0.5) == pytest.approx(0.05 * math.tanh(0.2))


def test_default_friction_width_keeps_explicit_coupling_monotone():
    """h mu/(omega_eps J_rotor) < 1: friction alone decays omega without sign flips at 1 ms."""
    for p in (motor1, motor2):
        omega = 0.3
        for _ in range(200):
            omega_new = omega - H * coulomb_friction(omega, p.mu, p.omega_eps) / p.J_rotor
            assert 0.0 <= omega_new < omega
            omega = omega_new


@pytest.mark.parametrize("name", ["i_ref", "v_ref", "omega", "i_hat", "h"])
def test_nan_input_named(name):
    """Catches a drive step that accepts NaN in an input or names the wrong input in its refusal."""
    args = {"i_ref": 0.0, "v_ref": 0.0, "omega": 0.0, "i_hat": 0.0, "h": H}
    args[name] = math.nan
    with pytest.raises(ValueError, match=rf"^{name} must be a finite number, got nan"):
        Drive(motor1).step(**args)


def test_bad_mode_method_and_step():
    """Catches a drive that accepts an unknown mode or method, a negative step, a step not dividing T, or L = 0."""
    with pytest.raises(ValueError, match=r"mode must be one of 'current', 'voltage'; got 'torque'"):
        Drive(motor1, mode="torque")
    with pytest.raises(ValueError, match="method must be one of"):
        Drive(motor1, method="rk4")
    with pytest.raises(ValueError, match="h must be > 0, got -0.001"):
        Drive(motor1).step(0, 0, 0, 0, -1e-3)
    with pytest.raises(ValueError, match="h must divide the controller period"):
        Drive(motor1).step(0, 0, 0, 0, 0.3e-3)
    with pytest.raises(ValueError, match="needs L > 0"):
        Drive(motor1.with_(L=0.0), mode="current")
    with pytest.raises(ValueError, match="needs L > 0"):
        electrical_step_coefficients(1.0, 0.0, H, "euler")


def test_mean_current_coefficients_are_the_step_average():
    """Catches mean-current weights that are not the integral average over the step (exact, Euler, quasi-static)."""
    import math

    from scipy.integrate import quad

    from motor.electrics import advance_current, electrical_step_coefficients, mean_current_coefficients

    R, ke, i0, v, omega = 1.101, 5.138e-2, 0.7, 6.0, 40.0
    u = v - ke * omega
    for L, h in ((0.667e-3, 1e-3), (0.667e-3, 0.25e-3), (1e-6, 1e-3), (5e-3, 1e-3)):
        tau = L / R
        breaks = [b * tau for b in (1, 5, 20, 80) if b * tau < h]      # the transient may be short
        exact, _ = quad(lambda s: u / R + (i0 - u / R) * math.exp(-s / tau), 0.0, h, epsabs=0, epsrel=1e-13,
                        points=breaks or None, limit=200)
        w_i, w_u = mean_current_coefficients(R, L, h, "exact")
        assert w_i * i0 + w_u * u == pytest.approx(exact / h, rel=1e-12)
        # Euler: the current is linear over the step; quasi-static: u / R throughout
        i1 = advance_current(i0, v, omega, ke, electrical_step_coefficients(R, L, h, "euler"))
        w_i, w_u = mean_current_coefficients(R, L, h, "euler")
        assert w_i * i0 + w_u * u == pytest.approx(0.5 * (i0 + i1), rel=1e-14)
    assert mean_current_coefficients(R, 0.667e-3, 1e-3, "quasi_static") == (0.0, 1.0 / R)
    assert mean_current_coefficients(R, 0.0, 1e-3, "exact") == (0.0, 1.0 / R)


@pytest.mark.parametrize("params", [motor1, motor2])
def test_armature_current_rate_gives_the_rl_circuit_exponential(params):
    """L di/dt = v - R i - ke omega (4.162) at constant v and omega is the RL circuit:
    i(t) = i_ss + (i0 - i_ss) exp(-R t / L), i_ss = (v - ke omega) / R.  Integrated with
    classical RK4 (600 steps over three time constants, error ~1e-10) from i0 = -0.2 A."""
    v, omega, i0 = 6.0, 40.0, -0.2
    i_ss, tau = (v - params.ke * omega) / params.R, params.L / params.R
    n, t_end = 600, 3.0 * tau
    h, i = t_end / n, i0

    def rate(current):
        return armature_current_rate(current, v, omega, params)

    for _ in range(n):
        k1 = rate(i)
        k2 = rate(i + 0.5 * h * k1)
        k3 = rate(i + 0.5 * h * k2)
        k4 = rate(i + h * k3)
        i += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    assert i == pytest.approx(i_ss + (i0 - i_ss) * math.exp(-3.0), rel=1e-7)


def test_a_non_finite_current_blames_eulers_divergence_only_when_h_exceeds_2_l_over_r():
    """Euler's current is multiplied by 1 - h R / L each step: beyond h = 2 L / R it grows
    without bound, and the refusal says so.  A current made infinite otherwise (a back-EMF
    ke omega of 1e310 V) at a stable h is refused without that explanation."""
    stable = Drive(motor1.with_(ke=1e300), mode="voltage", method="euler")
    assert 1e-4 < 2 * motor1.L / motor1.R
    with pytest.raises(kernels.Refused, match=r"armature current i = -inf A.* are not finite$") as info:
        stable.step(0.0, 1.0, 1e10, 0.0, 1e-4)
    assert "diverges" not in str(info.value)
    unstable = Drive(motor1, mode="voltage", method="euler")
    with pytest.raises(kernels.Refused, match=r"not finite: method 'euler' diverges for h = 0.002 s > 2 L/R = 0.00121 s "
                                              r"\(L = 0.000667 H, R = 1.101 ohm; the current is multiplied by "
                                              r"1 - hR/L = -2.3 every step\); use 'exact'"):
        for _ in range(3000):
            unstable.step(0.0, 1.0, 0.0, 0.0, 2e-3)


@pytest.mark.parametrize("v_ref", [3.5, -30.0, 30.0])
def test_a_voltage_mode_drive_samples_its_reference_clipped_to_v_max(v_ref):
    """Voltage mode applies v_ref itself, saturated at +-v_max (24 V), at any step h."""
    drive = Drive(motor1, mode="voltage")
    for h in (1e-4, 1e-3):
        assert drive.sample_voltage(0.0, v_ref, 0.0, h) == max(-24.0, min(24.0, v_ref))


@pytest.mark.parametrize("n", [1, 4])
def test_the_sample_phase_is_one_of_the_periods_n_steps_and_the_n_th_is_refused_word_for_word(n):
    """A period T of n steps h = T / n has steps 0 .. n - 1: sample_phase n - 1 (the last) steps,
    n itself is refused naming phase, n, h and T (the boundary a "> n" would let through, the
    controller then never sampling)."""
    T = 1e-3
    Drive(motor1, T=T, sample_phase=n - 1).step(0.0, 0.0, 0.0, 0.0, T / n)
    with pytest.raises(ValueError) as caught:
        Drive(motor1, T=T, sample_phase=n).step(0.0, 0.0, 0.0, 0.0, T / n)
    assert str(caught.value) == f"sample_phase = {n} must be below T / h = {n} (h = {T / n!r}, T = 0.001)"
