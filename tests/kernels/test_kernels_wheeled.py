"""The wheeled pendulum's and the balance controller's C kernels (kernels/src/wheeled.c,
balance.c) against oracles that share no code with them: the power balance of seed 000's
energy, RK4's order, the LQR design model's linearisation, the observer and LQR written
with numpy; and their refusals (nothing changed, every buffer index checked).

Cheap and free of sympy and FMUs, so that they also run against the sanitizer build
(``$PARCOSIM_KERNELS_LIB``)."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from controller import fastbalance
from plant import wheeled_kernel as K
from plant.wheeled import SEED, FallenError, WheeledPendulum, pack, refusal_error

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
    before, b = sim.y.copy(), K.calls(sim)
    code = b.step(0.0, 0.0, 0.0, 4 * h, 4)
    assert code == K.FALLEN_PITCH and b.taken.value == falls_at and 1 < falls_at
    assert b.refusal.value == psi and abs(psi) >= math.pi / 2 and np.array_equal(sim.y, before)


@pytest.mark.parametrize("index, value, code", [(0, math.nan, K.BAD_INPUT), (1, math.inf, K.BAD_INPUT),
                                                (2, 2e6, K.INPUT_LIMIT)])
def test_the_io_step_refuses_an_input_and_changes_nothing(index, value, code):
    """Catches a pendulum I/O step that accepts a bad input or changes its state or outputs."""
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
    assert K.step_io(sim.prm, sim.y, settings, x, 0.0, 1e-3, refusal) == K.BAD_SETTING
    assert refusal.index == (0 if count == 1e-3 else 1)
    message = str(refusal_error(refusal, 0.5, 0.0))
    assert message.startswith(f"setting {('substeps', 'count')[refusal.index]} = ") and "t = 0.5 s" in message


def test_the_io_step_is_the_step_with_the_push_then_the_sensors():
    """pc_wheeled_step_io adds the push over the steps that start in its window and reads
    the sensors of the new state: it reads its 3 inputs only (the output words hold NaN before
    the call), writes every output and nothing past them (a sentinel after the array).  Catches a
    push window or torque misapplied, an input loop one word too long, an output left unwritten."""
    settings = np.zeros(K.SETTINGS_SIZE)
    settings[K.S_SUBSTEPS], settings[K.S_COUNT], settings[K.S_LIMIT] = 2, 2 * math.pi / 4096, 1e6
    settings[K.S_PUSH_TORQUE], settings[K.S_PUSH_START], settings[K.S_PUSH_DURATION] = 0.3, 0.002, 0.002
    io_sim, sim = WheeledPendulum(initial=dict(psi=0.05)), WheeledPendulum(initial=dict(psi=0.05))
    for k in range(5):
        t = k * 1e-3
        x = np.full(3 + len(K.OUTPUT_NAMES) + 1, np.nan)
        x[:3], x[-1] = (0.01, -0.02, 0.001), -123456.75
        assert K.step_io(io_sim.prm, io_sim.y, settings, x, t, 1e-3, kernels.Refusal()) == K.OK
        assert x[-1] == -123456.75
        x = x[:-1]
        sim.step(0.01, -0.02, 1e-3, 0.001 + (0.3 if 0.002 - 1e-9 <= t < 0.004 - 1e-9 else 0.0))
        np.testing.assert_array_equal(io_sim.y, sim.y)
        assert dict(zip(K.OUTPUT_NAMES, x[3:].tolist())) == sim.outputs()


def _smooth(t, start, end):
    """(s, s') of (7.27) in closed form over the window [start, end]."""
    tau = min(max((t - start) / (end - start), 0.0), 1.0)
    s = 35 * tau ** 4 - 84 * tau ** 5 + 70 * tau ** 6 - 20 * tau ** 7
    ds = (140 * tau ** 3 - 420 * tau ** 4 + 420 * tau ** 5 - 140 * tau ** 6) / (end - start)
    return s, ds


def _design(yaw: bool, seed: int = 5):
    """A design of random matrices (the C sample must not care where they came from) with
    the kept states and measurements of controller.balance, and the forward_turn route."""
    from types import SimpleNamespace

    rng = np.random.default_rng(seed)
    states = (0, 1, 2, 3, 4, 5) if yaw else (0, 1, 3, 4)
    n, ny = len(states), 3 if yaw else 2
    design = SimpleNamespace(states=states, K=rng.normal(0, 20, (2, n)), Lo=rng.normal(0, 0.3, (n, ny)),
                             C=rng.normal(0, 1, (ny, n)), Ad=np.eye(n) + rng.normal(0, 1e-2, (n, n)),
                             Bd=rng.normal(0, 1e-2, (n, 2)), settings=SimpleNamespace(yaw=yaw, v_battery=2.0))
    route = SimpleNamespace(distance=1.0, turn=0.5 * math.pi, drive=(0.5, 5.5), turning=(6.0, 8.0))
    return design, route


def numpy_balance(design, route, yaw: bool, samples: int):
    """controller/balance.py's docstring in matrix form, written with numpy: per sample (every
    20 ms, noisy encoders and gyro), ``(t, (enc_l, enc_r, gyro), u, x_hat, x_d)`` with the
    command u (saturated at 2 V) and the predicted estimate x_hat after it; the first sample
    starts at rest at the encoders' theta - psi; the route's smooth steps (7.27) in closed form."""
    rng = np.random.default_rng(4)
    states, x_hat = list(design.states), None
    for k in range(samples):
        t = 0.02 * k
        enc_l, enc_r, gyro = rng.normal(0.0, 0.05, 3) + (0.3 * t, 0.35 * t, 0.0)
        y = np.array([0.5 * (enc_l + enc_r), gyro] + ([0.04 / 0.14 * (enc_r - enc_l)] if yaw else []))
        if x_hat is None:
            x_hat = np.array([y[0], 0.0, y[2] if yaw else 0.0, 0.0, gyro, 0.0])[states]
        x_hat = x_hat + design.Lo @ (y - design.C @ x_hat)
        (s, ds), (a, da) = _smooth(t, *route.drive), _smooth(t, *route.turning)
        reference = np.array([s * route.distance / 0.04, 0.0, a * route.turn, ds * route.distance / 0.04, 0.0,
                              da * route.turn])[states]
        u = np.clip(-design.K @ (x_hat - reference), -2.0, 2.0)
        x_hat = design.Ad @ x_hat + design.Bd @ u
        yield t, (enc_l, enc_r, gyro), u, x_hat, s * route.distance


def _buffer(yaw: bool = True) -> np.ndarray:
    from controller.trajectories import SMOOTHSTEP_COEFFICIENTS, SMOOTHSTEP_SLOPE_COEFFICIENTS

    design, route = _design(yaw)
    return fastbalance.pack(design, route, 0.04, 0.14, 0.35, SMOOTHSTEP_COEFFICIENTS, SMOOTHSTEP_SLOPE_COEFFICIENTS)


@pytest.mark.parametrize("yaw", [True, False])
def test_the_balance_sample_is_the_observer_and_lqr_written_with_numpy(yaw):
    """controller/balance.py's docstring in matrix form: correct, command (saturated),
    predict; the first sample starts at rest at the encoders' theta - psi."""
    design, route = _design(yaw)
    buf, x, refusal = _buffer(yaw), np.zeros(fastbalance.IO_SIZE), kernels.Refusal()
    states = list(design.states)
    for t, sensors, u, x_hat, x_d in numpy_balance(design, route, yaw, 450):
        x[:3] = sensors
        assert fastbalance.sample(buf, x, t, 1e6, refusal) == fastbalance.OK
        out = dict(zip(fastbalance.OUTPUTS, x[3:]))
        np.testing.assert_allclose([out["v_l"], out["v_r"], out["tau_l"], out["tau_r"]], [*u, *(0.35 * u)],
                                   rtol=1e-11, atol=1e-11)
        full = np.zeros(6)
        full[states] = x_hat
        np.testing.assert_allclose(x[fastbalance.O_HAT:], full, rtol=1e-10, atol=1e-11)
        assert out["x_d"] == pytest.approx(x_d, rel=1e-12, abs=1e-15) and out["y_d"] == 0.0
    assert np.any(np.abs(u) == 2.0), "the run should reach the saturation"


@pytest.mark.parametrize("word, value", [("n", 7.0), ("n", -1.0), ("n", 2.5), ("ny", 4.0), ("ny", math.nan),
                                         ("states", 6.0), ("states", -1.0), ("states", 1e300)])
def test_the_balance_sample_refuses_a_size_or_index_outside_its_arrays(word, value):
    """The controller indexes its arrays with words of its buffer (sizes, kept-state
    indices): a forged word is refused by index and value before anything is read or
    written, the buffer and the I/O array unchanged."""
    buf, x, refusal = _buffer(), np.zeros(fastbalance.IO_SIZE), kernels.Refusal()
    x[:3] = 0.01, 0.02, 0.0
    assert fastbalance.sample(buf, x, 0.0, math.inf, refusal) == fastbalance.OK
    index = fastbalance.BUFFER[word].start + (3 if word == "states" else 0)
    buf[index] = value
    before, x_before = buf.copy(), x.copy()
    assert fastbalance.sample(buf, x, 0.001, math.inf, refusal) == fastbalance.BAD_BUFFER
    assert refusal.index == index and (refusal.value == value or math.isnan(value))
    assert np.array_equal(buf, before, equal_nan=True) and np.array_equal(x, x_before)
    assert fastbalance.WORD_NAMES[index] == (f"{word}[3]" if word == "states" else word)


@pytest.mark.parametrize("index, value, limit, code", [(2, math.nan, math.inf, fastbalance.BAD_INPUT),
                                                       (0, math.inf, math.inf, fastbalance.BAD_INPUT),
                                                       (1, -2e6, 1e6, fastbalance.INPUT_LIMIT)])
def test_the_balance_sample_refuses_an_input_and_changes_nothing(index, value, limit, code):
    """Catches a balance sample that accepts a bad input or changes its buffer or outputs."""
    buf, x, refusal = _buffer(yaw=False), np.zeros(fastbalance.IO_SIZE), kernels.Refusal()
    x[index] = value
    before, x_before = buf.copy(), x.copy()
    assert fastbalance.sample(buf, x, 0.25, limit, refusal) == code
    assert (refusal.index, refusal.value) == (index, value) or math.isnan(value)
    assert np.array_equal(buf, before) and np.array_equal(x, x_before, equal_nan=True)


def test_the_balance_buffer_layout_is_params_then_run_state():
    """run_state_words (what an FMU state may change) is exactly pc_balance_state's words:
    started, the estimate, the voltages; the sizes and indices are configuration."""
    words = set(fastbalance.RUN_STATE_WORDS)
    assert {fastbalance.B_STARTED, fastbalance.B_U, fastbalance.B_U + 1} <= words
    assert set(range(fastbalance.B_X_HAT, fastbalance.B_X_HAT + fastbalance.N_MAX)) <= words
    assert len(words) == 1 + fastbalance.N_MAX + 2
    assert not {fastbalance.B_N, fastbalance.B_NY, *range(fastbalance.B_STATES, fastbalance.B_STATES + 6)} & words


def test_every_refusal_code_has_its_message():
    """A code without a Reason would end in a KeyError instead of the refusal's message."""
    from plant.wheeled import REASONS

    assert set(REASONS) == {K.FALLEN_PITCH, K.FALLEN_FLOOR, K.NONFINITE, K.BAD_INPUT, K.BAD_STEP, K.INPUT_LIMIT,
                            K.BAD_SETTING}
    refusal = kernels.Refusal(code=K.INPUT_LIMIT, index=2, value=2e6)
    assert str(refusal_error(refusal, 0.001, 0.0, limit=1e6)) == \
        "input tau_d = 2000000.0 at t = 0.001 s is absurd: |tau_d| must be <= 1e+06"


@pytest.mark.parametrize("index", [0, 1, 2])
def test_the_balance_sample_takes_an_input_at_the_limit_and_refuses_one_double_beyond(index):
    """controller/balance.py's refusal reads "|input| must be <= limit": an input of magnitude
    equal to the limit is taken (either sign), the next double beyond it is refused with
    INPUT_LIMIT, its index and value, the buffer unchanged (a boundary never met exactly:
    the sibling of training seed 4251's [4])."""
    limit = 0.75
    for sign in (1.0, -1.0):
        buf, x, refusal = _buffer(), np.zeros(fastbalance.IO_SIZE), kernels.Refusal()
        x[index] = sign * limit
        assert fastbalance.sample(buf, x, 0.0, limit, refusal) == fastbalance.OK
        x[:] = 0.0
        x[index] = sign * np.nextafter(limit, np.inf)
        before = buf.copy()
        assert fastbalance.sample(buf, x, 0.001, limit, refusal) == fastbalance.INPUT_LIMIT
        assert (refusal.code, refusal.index, refusal.value) == (fastbalance.INPUT_LIMIT, index, x[index])
        assert np.array_equal(buf, before)
