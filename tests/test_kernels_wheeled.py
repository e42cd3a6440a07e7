"""The wheeled pendulum's and the balance controller's C kernels (kernels/src/wheeled.c,
balance.c) against oracles that share no code with them: the power balance of seed 000's
energy, RK4's order, the LQR design model's linearisation, the observer and LQR written
with numpy; and their refusals (nothing changed, every buffer index checked).

Cheap and free of sympy and FMUs, so that they also run against the sanitizer build
(``$PARCOSIM_KERNELS_LIB``)."""
from __future__ import annotations

import ctypes
import math
import re

import numpy as np
import pytest

import kernels
from controller import fastbalance
from plant import wheeled_kernel as K
from plant.wheeled import SEED, FallenError, WheeledPendulum, pack

SIX = [K.THETA, K.PSI, K.PHI, K.DTHETA, K.DPSI, K.DPHI]


def _random_state(rng) -> np.ndarray:
    y = np.zeros(K.N_STATE)
    y[[K.THETA, K.PHI, K.X, K.Y]] = rng.uniform(-2.0, 2.0, 4)
    y[K.PSI] = rng.uniform(-1.0, 1.0)
    y[[K.DTHETA, K.DPSI, K.DPHI]] = rng.uniform(-5.0, 5.0, 3)
    return y


@pytest.mark.parametrize("model", ["exact", "seed"])
def test_the_energy_changes_at_the_power_of_the_torques(model):
    """dE/dt along the C derivative = tau_l omega_l + tau_r omega_r + tau_d psi' at random
    states (constraint forces and the gyroscopic terms do no work).  dE/dt is the central
    difference of the C energy along y' (an independent check of (17)-(20) against (8)-(12):
    a wrong sign or factor in any term of M, C, G or F breaks it)."""
    prm = pack(SEED, model)
    rng = np.random.default_rng(3)
    dy, sensed = np.empty(K.N_STATE), np.empty(len(K.OUTPUT_NAMES))
    for _ in range(25):
        y = _random_state(rng)
        tau_l, tau_r, tau_d = rng.uniform(-0.2, 0.2, 3)
        K.derivative(prm, y, tau_l, tau_r, tau_d, dy)
        eps = 1e-6
        rate = (K.energy(prm, y + eps * dy) - K.energy(prm, y - eps * dy)) / (2 * eps)
        K.sensors(prm, y, 1e-3, sensed)
        omega_l, omega_r = sensed[K.OUTPUT_NAMES.index("omega_l")], sensed[K.OUTPUT_NAMES.index("omega_r")]
        power = tau_l * omega_l + tau_r * omega_r + tau_d * y[K.DPSI]
        assert rate == pytest.approx(power, rel=1e-6, abs=1e-9)


def test_rk4_is_fourth_order():
    """Halving the step divides the error of 0.2 s of a turning, tipping motion by ~16 (RK4:
    pc_rk4 with the substep h = dt / substeps; a wrong stage weight or h makes it 2 or 4)."""
    start = dict(psi=0.05, dtheta=2.0, dphi=3.0, dpsi=-1.0)

    def end(substeps):
        sim = WheeledPendulum(initial=start, substeps=substeps)
        for _ in range(20):
            sim.step(0.0, 0.0, 1e-2)
        return sim.y.copy()

    fine = end(64)
    errors = [np.max(np.abs(end(n)[SIX] - fine[SIX])) for n in (1, 2, 4)]
    assert errors[0] > 1e-5, "the motion should be large enough to show the error"
    for coarse, finer in zip(errors, errors[1:]):
        assert 12.0 < coarse / finer < 20.0, errors


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


def test_a_fall_changes_nothing_and_names_the_substep():
    """A step whose k-th of four substeps passes 90 degrees keeps the state and reports k
    and that pitch: the same substeps taken one by one fall at the k-th."""
    start, h = dict(psi=1.5, dpsi=3.0), 0.0075
    one_by_one = WheeledPendulum(initial=start, substeps=1)
    for k in range(1, 5):
        try:
            one_by_one.step(0.0, 0.0, h)
        except FallenError as exc:
            falls_at, psi = k, exc.value
            break
    sim = WheeledPendulum(initial=start, substeps=4)
    before, refusal, b = sim.y.copy(), kernels.Refusal(), sim._bound()
    code = K._step(*b.addresses, 0.0, 0.0, 0.0, 4 * h, 4, b.taken_address, ctypes.addressof(refusal))
    assert code == K.FALLEN_PITCH and b.taken.value == falls_at and 1 < falls_at
    assert refusal.value == psi and abs(psi) >= math.pi / 2 and np.array_equal(sim.y, before)


@pytest.mark.parametrize("index, value, code", [(0, math.nan, K.BAD_INPUT), (1, math.inf, K.BAD_INPUT),
                                                (2, 2e6, K.INPUT_LIMIT)])
def test_the_io_step_refuses_an_input_and_changes_nothing(index, value, code):
    sim = WheeledPendulum(initial=dict(psi=0.05))
    settings = np.zeros(K.SETTINGS_SIZE)
    settings[K.S_SUBSTEPS], settings[K.S_COUNT], settings[K.S_LIMIT] = 2, 1e-3, 1e6
    x = np.zeros(3 + len(K.OUTPUT_NAMES))
    x[index] = value
    before, x_before = sim.y.copy(), x.copy()
    refusal = kernels.Refusal()
    assert K.step_io(sim.prm, sim.y, settings, x, 0.0, 1e-3, refusal) == code
    assert refusal.index == index and np.array_equal(sim.y, before)
    np.testing.assert_array_equal(x, x_before)


@pytest.mark.parametrize("substeps, count", [(0.0, 1e-3), (2.5, 1e-3), (1e300, 1e-3), (math.nan, 1e-3),
                                             (2.0, 0.0), (2.0, math.nan)])
def test_the_io_step_refuses_forged_settings(substeps, count):
    """The substep count is cast to int only when it is an integer in [1, MAX_SUBSTEPS]
    (a cast of 1e300 is undefined behaviour), the encoder count must be > 0."""
    sim = WheeledPendulum()
    settings = np.zeros(K.SETTINGS_SIZE)
    settings[K.S_SUBSTEPS], settings[K.S_COUNT], settings[K.S_LIMIT] = substeps, count, 1e6
    x = np.zeros(3 + len(K.OUTPUT_NAMES))
    refusal = kernels.Refusal()
    assert K.step_io(sim.prm, sim.y, settings, x, 0.0, 1e-3, refusal) == K.BAD_STEP
    assert refusal.index == (1 if count == 1e-3 else 2)


def test_the_io_step_is_the_step_with_the_push_then_the_sensors():
    """pc_wheeled_step_io adds the push over the steps that start in its window and reads
    the sensors of the new state."""
    settings = np.zeros(K.SETTINGS_SIZE)
    settings[K.S_SUBSTEPS], settings[K.S_COUNT], settings[K.S_LIMIT] = 2, 2 * math.pi / 4096, 1e6
    settings[K.S_PUSH_TORQUE], settings[K.S_PUSH_START], settings[K.S_PUSH_DURATION] = 0.3, 0.002, 0.002
    io_sim, sim = WheeledPendulum(initial=dict(psi=0.05)), WheeledPendulum(initial=dict(psi=0.05))
    for k in range(5):
        t = k * 1e-3
        x = np.zeros(3 + len(K.OUTPUT_NAMES))
        x[:3] = 0.01, -0.02, 0.001
        assert K.step_io(io_sim.prm, io_sim.y, settings, x, t, 1e-3, kernels.Refusal()) == K.OK
        sim.step(0.01, -0.02, 1e-3, 0.001 + (0.3 if 0.002 - 1e-9 <= t < 0.004 - 1e-9 else 0.0))
        np.testing.assert_array_equal(io_sim.y, sim.y)
        assert dict(zip(K.OUTPUT_NAMES, x[3:].tolist())) == sim.outputs()


def _controller(yaw=True):
    from controller.balance import BalanceController, BalanceSettings, design_balance, get_route

    return BalanceController(design_balance(BalanceSettings(yaw=yaw)), get_route("forward_turn"))


@pytest.mark.parametrize("word, value", [("n", 7.0), ("n", -1.0), ("n", 2.5), ("ny", 4.0), ("ny", math.nan),
                                         ("states", 6.0), ("states", -1.0), ("states", 1e300)])
def test_the_balance_sample_refuses_a_size_or_index_outside_its_arrays(word, value):
    """The controller indexes its arrays with words of its buffer (sizes, kept-state
    indices): a forged word is refused by index and value before anything is read or
    written, the buffer and the I/O array unchanged."""
    controller = _controller()
    controller.sample(0.0, 0.01, 0.02, 0.0)
    index = fastbalance.BUFFER[word].start + (3 if word == "states" else 0)
    controller.buf[index] = value
    buf, io = controller.buf.copy(), controller.io.copy()
    io[:3] = 0.01, 0.02, 0.0
    x = io.copy()
    refusal = kernels.Refusal()
    assert fastbalance.sample(controller.buf, x, 0.001, math.inf, refusal) == fastbalance.BAD_BUFFER
    assert refusal.index == index and (refusal.value == value or math.isnan(value))
    assert np.array_equal(controller.buf, buf, equal_nan=True) and np.array_equal(x, io)
    with pytest.raises(kernels.Refused, match="buffer word " + re.escape(fastbalance.WORD_NAMES[index])):
        controller.sample(0.001, 0.01, 0.02, 0.0)


def test_the_balance_sample_refuses_a_non_finite_input_by_name_and_time():
    controller = _controller(yaw=False)
    with pytest.raises(kernels.Refused, match=r"input gyro = nan at t = 0.25 s is not finite") as caught:
        controller.sample(0.25, 0.0, 0.0, math.nan)
    assert caught.value.variable == "gyro" and caught.value.time == 0.25 and controller.x_hat is None


def test_the_balance_buffer_layout_is_params_then_run_state():
    """run_state_words (what an FMU state may change) is exactly pc_balance_state's words:
    started, the estimate, the voltages; the sizes and indices are configuration."""
    words = set(fastbalance.RUN_STATE_WORDS)
    assert {fastbalance.B_STARTED, fastbalance.B_U, fastbalance.B_U + 1} <= words
    assert set(range(fastbalance.B_X_HAT, fastbalance.B_X_HAT + fastbalance.N_MAX)) <= words
    assert len(words) == 1 + fastbalance.N_MAX + 2
    assert not {fastbalance.B_N, fastbalance.B_NY, *range(fastbalance.B_STATES, fastbalance.B_STATES + 6)} & words
