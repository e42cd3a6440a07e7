"""The wheeled pendulum's simulator: accuracy, energy, linearisation, falling, refusals."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from plant import wheeled_kernel as K
from plant.wheeled import MAX_SUBSTEPS, SEED, FallenError, WheeledPendulum, pack, upright_linearisation

START = dict(psi=0.1, dphi=1.0, dtheta=2.0)
SIX = [K.THETA, K.PSI, K.PHI, K.DTHETA, K.DPSI, K.DPHI]


def torques(k):
    return 0.05 * math.sin(7e-3 * k), 0.04 * math.cos(5e-3 * k)


def test_default_integrator_within_1e_9_rad_of_a_tight_solution():
    """150 steps of 1 ms with held torques while it turns and falls to about -50 degrees."""
    sim = WheeledPendulum(initial=START)
    ref = WheeledPendulum(initial=START)
    y = sim.y.copy()
    worst = 0.0
    for k in range(150):
        sim.step(*torques(k), 1e-3)
        sol = solve_ivp(lambda _, z: ref.derivative(z, *torques(k)), (0.0, 1e-3), y, method="DOP853",
                        rtol=1e-13, atol=1e-14)
        y = sol.y[:, -1]
        worst = max(worst, float(np.max(np.abs(sim.y[:3] - y[:3]))))
    assert abs(sim.y[K.PSI]) > 0.5, "the run should be a large motion"
    assert worst <= 1e-9, f"largest angle error {worst:.3g} rad"


@pytest.mark.parametrize("model", ["exact", "seed"])
def test_energy_conserved_without_inputs(model):
    """Rolling constraints do no work; the seed's missing terms are gyroscopic (no power) too."""
    sim = WheeledPendulum(model=model, initial=dict(psi=0.05, dtheta=3.0, dphi=4.0, dpsi=-0.5), substeps=4)
    e0 = sim.energy()
    drift = 0.0
    for _ in range(200):
        sim.step(0.0, 0.0, 1e-3)
        drift = max(drift, abs(sim.energy() - e0))
    assert abs(sim.y[K.PSI]) > 0.3 and abs(sim.y[K.DPHI]) > 1.0
    assert drift <= 1e-10 * abs(e0), f"energy drift {drift:.3g} J of {e0:.3g} J"


def test_energy_balance_with_motor_torques():
    """With torques, dE/dt = tau_l omega_l + tau_r omega_r (the motors' power)."""
    sim = WheeledPendulum(initial=dict(psi=0.05, dtheta=1.0, dphi=2.0), substeps=8)
    work = 0.0
    e0 = sim.energy()
    for k in range(100):
        tl, tr = torques(k)
        before = sim.outputs()
        sim.step(tl, tr, 1e-4)
        after = sim.outputs()
        work += 1e-4 * 0.5 * (tl * (before["omega_l"] + after["omega_l"]) + tr * (before["omega_r"] + after["omega_r"]))
    assert sim.energy() - e0 == pytest.approx(work, rel=1e-5)


def test_linearisation_matches_finite_differences():
    """Catches a wrong entry of the upright linearisation A, B (differences of the nonlinear model)."""
    A, B = upright_linearisation()
    sim = WheeledPendulum()
    order = [K.THETA, K.PSI, K.PHI, K.DTHETA, K.DPSI, K.DPHI]

    def f(x, u):
        y = np.zeros(K.N_STATE)
        y[order] = x
        return sim.derivative(y, *u)[order]

    eps = 1e-6
    A_fd = np.column_stack([(f(eps * e, (0, 0)) - f(-eps * e, (0, 0))) / (2 * eps) for e in np.eye(6)])
    B_fd = np.column_stack([(f(np.zeros(6), eps * e) - f(np.zeros(6), -eps * e)) / (2 * eps) for e in np.eye(2)])
    np.testing.assert_allclose(A, A_fd, rtol=1e-7, atol=1e-7)
    np.testing.assert_allclose(B, B_fd, rtol=1e-7, atol=1e-7)
    assert np.max(np.linalg.eigvals(A).real) > 5.0, "upright is unstable"


def test_fall_is_reported_with_psi_and_time_and_keeps_the_state():
    sim = WheeledPendulum(initial=dict(psi=0.2))
    with pytest.raises(FallenError) as caught:
        for _ in range(2000):
            sim.step(0.0, 0.0, 1e-3)
    err = caught.value
    assert err.code == K.FALLEN_PITCH and sim.fallen
    assert 0.1 < err.time < 2.0 and "psi = " in str(err) and f"t = {err.time:.6g} s" in str(err)
    assert np.all(np.isfinite(sim.y)) and abs(sim.y[K.PSI]) < 0.5 * math.pi
    assert sim.time < err.time <= sim.time + 1e-3
    # one refusal record (kernels.Refused): psi past 90 degrees at the end of the failing substep
    record = err.record()
    assert (record["variable"], record["unit"], record["reason"], record["time"]) == ("psi", "rad", "fallen_pitch",
                                                                                      err.time)
    assert abs(record["value"]) >= 0.5 * math.pi and record["message"] == str(err)


def test_body_touching_the_floor_is_a_fall():
    """A body deeper than twice the wheel radius hits the floor before 90 degrees."""
    sim = WheeledPendulum(SEED.with_(D=0.2), initial=dict(psi=0.3))
    with pytest.raises(FallenError) as caught:
        for _ in range(2000):
            sim.step(0.0, 0.0, 1e-3)
    assert caught.value.code == K.FALLEN_FLOOR
    touch = math.asin(SEED.R / 0.1)   # R = (D/2) sin psi: about 23.6 degrees
    assert touch - 0.05 < abs(caught.value.psi) <= touch


def test_yaw_locked_keeps_heading():
    """Catches a yaw-locked pendulum whose heading, yaw rate or lateral position moves."""
    sim = WheeledPendulum(yaw=False, initial=dict(psi=0.05))
    for _ in range(100):
        sim.step(0.01, -0.01, 1e-3)
    assert sim.y[K.PHI] == 0.0 and sim.y[K.DPHI] == 0.0 and sim.y[K.Y] == 0.0


@pytest.mark.parametrize("call, text", [
    (lambda s: s.step(float("nan"), 0.0, 1e-3), "input tau_l = nan at t = 0 s"),
    (lambda s: s.step(0.0, 0.0, -1.0), "step size -1.0 at t = 0 s"),
])
def test_bad_input_named(call, text):
    """Catches a pendulum step that accepts a non-finite input or names the wrong one."""
    sim = WheeledPendulum()
    with pytest.raises(ValueError, match=text.replace("(", r"\(")):
        call(sim)


def test_bad_parameters_named():
    """Catches a pendulum built with a negative mass, a pitch past 90 degrees or an unknown model."""
    with pytest.raises(ValueError, match="parameter M = -1"):
        WheeledPendulum(SEED.with_(M=-1.0))
    with pytest.raises(ValueError, match=r"initial psi = 2.0 rad is no standing robot \(fallen_pitch\)") as fallen:
        WheeledPendulum(initial=dict(psi=2.0))
    assert (fallen.value.name, fallen.value.value) == ("psi", 2.0)
    with pytest.raises(ValueError, match="model = 'other'"):
        WheeledPendulum(model="other")


def test_balance_design_body_torque_column_is_the_plant_s_response():
    """The observer's process noise enters as a body torque through d x'/d tau_d at the
    upright (controller.balance); the plant's own derivative (seed 000 (18)-(20), exact
    model) gives that column: the accelerations per N m of tau_d, nothing on the angles."""
    from controller.balance import _body_torque_column
    prm = pack(SEED)
    y, out = np.zeros(K.N_STATE), np.zeros(K.N_STATE)
    rates = []
    for tau_d in (1.0, -1.0):
        K.derivative(prm, y, 0.0, 0.0, tau_d, out)
        rates.append(out[[K.THETA, K.PSI, K.PHI, K.DTHETA, K.DPSI, K.DPHI]].copy())
    column = (rates[0] - rates[1]) / 2.0
    assert abs(column[4]) > 0.0                   # a body torque tilts the body
    np.testing.assert_allclose(_body_torque_column(None), column, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("counts", [7, 2048])
def test_encoders_read_the_count_nearest_to_the_wheel_relative_to_the_body(counts):
    """A wheel encoder measures its wheel's angle relative to the body: θ ∓ (W/2R) φ − ψ
    (seed 000 (10): θ_l,r = θ ∓ (W/2R) φ, the encoder's stator turns with the body).  It reads
    the multiple of 2π/N nearest to that angle; N = 7 makes a count 0.9 rad, so rounding down
    or up by half a count cannot pass."""
    prm = pack(SEED)
    count = 2 * math.pi / counts
    half = SEED.W / (2 * SEED.R)
    out = np.empty(len(K.OUTPUT_NAMES))
    rng = np.random.default_rng(7)
    for _ in range(20):
        y = np.zeros(K.N_STATE)
        y[[K.THETA, K.PSI, K.PHI]] = rng.uniform(-3.0, 3.0, 3)
        K.sensors(prm, y, count, out)
        relative = (y[K.THETA] - half * y[K.PHI] - y[K.PSI], y[K.THETA] + half * y[K.PHI] - y[K.PSI])
        for name, angle in zip(("enc_l", "enc_r"), relative):
            reading = out[K.OUTPUT_NAMES.index(name)]
            assert abs(reading / count - round(reading / count)) < 1e-9
            assert abs(reading - angle) <= count / 2 + 1e-12


@pytest.mark.parametrize("counts", [1, 7, 4096])
def test_pendulum_encoders_have_counts_per_turn(counts):
    """``encoder_counts`` N is counts per wheel turn: a turning wheel's readings are multiples
    of 2π/N and within half a count of the relative angle (N = 1 is a legal, coarse encoder)."""
    pendulum = WheeledPendulum(initial={"theta": 2.9, "psi": 0.05, "phi": 0.4}, encoder_counts=counts)
    count = 2 * math.pi / counts
    out = pendulum.outputs()
    half = SEED.W / (2 * SEED.R)
    relative = {"enc_l": 2.9 - half * 0.4 - 0.05, "enc_r": 2.9 + half * 0.4 - 0.05}
    for name, angle in relative.items():
        assert abs(out[name] / count - round(out[name] / count)) < 1e-9
        assert abs(out[name] - angle) <= count / 2 + 1e-12


@pytest.mark.parametrize("substeps", [0, MAX_SUBSTEPS + 1])
def test_pendulum_substeps_beyond_their_bounds_are_refused(substeps):
    with pytest.raises(ValueError, match=f"substeps = {substeps}"):
        WheeledPendulum(substeps=substeps)
    WheeledPendulum(substeps=MAX_SUBSTEPS)        # the bound itself is allowed


def test_the_c_derivative_linearises_to_the_lqr_design_model():
    """Finite differences of the C derivative, with the drives of seed 000 (22) in front
    (tau = (K_t/R_m) v - c omega), at the upright at rest, give the (A, B) the balance
    controller is designed on (controller.balance.voltage_model)."""
    from controller.balance import BalanceSettings, voltage_model
    from motor import get_motor_preset

    settings = BalanceSettings()
    A_design, B_design = voltage_model(settings)
    motor = get_motor_preset(settings.motor_preset)
    c = motor.kt * motor.ke / motor.R + motor.b
    half = SEED.W / (2 * SEED.R)
    prm = pack(SEED)

    def f(x, v):
        y = np.zeros(K.N_STATE)
        y[SIX] = x
        omega_l = x[3] - half * x[5] - x[4]
        omega_r = x[3] + half * x[5] - x[4]
        dy = np.empty(K.N_STATE)
        K.derivative(prm, y, motor.kt / motor.R * v[0] - c * omega_l, motor.kt / motor.R * v[1] - c * omega_r, 0.0,
                     dy)
        return dy[SIX]

    eps = 1e-6
    A = np.column_stack([(f(eps * e, (0, 0)) - f(-eps * e, (0, 0))) / (2 * eps) for e in np.eye(6)])
    B = np.column_stack([(f(np.zeros(6), eps * e) - f(np.zeros(6), -eps * e)) / (2 * eps) for e in np.eye(2)])
    np.testing.assert_allclose(A, A_design, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(B, B_design, rtol=1e-6, atol=1e-6)


def test_the_balance_controller_refuses_a_non_finite_input_by_name_and_time():
    """The C sample's refusal becomes one kernels.Refused with the slave's text; nothing starts."""
    import kernels
    from controller.balance import BalanceController, BalanceSettings, design_balance

    controller = BalanceController(design_balance(BalanceSettings(yaw=False)))
    with pytest.raises(kernels.Refused, match=r"input gyro = nan at t = 0.25 s is not finite") as caught:
        controller.sample(0.25, 0.0, 0.0, math.nan)
    assert (caught.value.variable, caught.value.time) == ("gyro", 0.25) and controller.x_hat is None


def test_every_balance_refusal_code_has_its_message():
    """Catches a balance controller refusal code without its message (a KeyError where the refusal is
    reported) or a message naming the wrong buffer word."""
    import kernels
    from controller import fastbalance
    from controller.balance import REASONS

    assert set(REASONS) == {fastbalance.BAD_INPUT, fastbalance.INPUT_LIMIT, fastbalance.BAD_BUFFER}
    refusal = kernels.Refusal(code=fastbalance.BAD_BUFFER, index=fastbalance.B_STATES + 2, value=9.0)
    assert str(kernels.refused(REASONS, refusal, 0.5, limit=1e6)).startswith(
        "the balance controller's buffer word states[2] = 9.0 at t = 0.5 s")
