"""The drive's and the observer's C kernels (kernels/src/drive.c, observer.c) against oracles
that share no code with them: scipy's matrix exponential and ODE solver for the electrics,
python-control's simulation of the designed K(z), the Stribeck curve of the LuGre paper,
SplitMix64's published outputs and a Python SplitMix64, and the refusal contract (a code,
the quantity, its value; nothing changed)."""
from __future__ import annotations

import ctypes
import math

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

import kernels
from motor import CurrentObserver, Drive, friction as fr, kernel, motor1, motor2
from motor.drive import gaussian, uniform

H = 1e-3
MASK = 2 ** 64 - 1


@pytest.mark.parametrize("params", [motor1, motor2], ids=["motor1", "motor2"])
@pytest.mark.parametrize("h", [1e-4, 1e-3, 2e-2])
def test_exact_electrics_are_the_matrix_exponential_and_the_ode(params, h):
    """Voltage mode, v and omega held: i(h) of L di/dt = v - R i - ke omega is expm of the
    augmented system [[-R/L, 1/L], [0, 0]] h applied to (i0, v - ke omega), and what solve_ivp
    (DOP853, rtol 1e-12) integrates; the mean torque is kt times the current's mean (quad of
    the same exponential) minus B.2's friction."""
    v, omega, i0 = 0.6 * params.v_max, 3.0, 0.4
    drive = Drive(params, mode="voltage", torque_output="mean")
    drive.reset(i0, v)
    tau, v_applied, i = drive.step(0.0, v, omega, 0.0, h)
    R, L, ke = params.R, params.L, params.ke
    u = v - ke * omega
    augmented = np.array([[-R / L, 1.0 / L], [0.0, 0.0]])
    i_expm = (expm(augmented * h) @ [i0, u])[0]
    ode = solve_ivp(lambda t, y: [(v - R * y[0] - ke * omega) / L], (0.0, h), [i0], method="DOP853",
                    rtol=1e-12, atol=1e-15)
    assert v_applied == v
    assert i == pytest.approx(i_expm, rel=1e-12, abs=1e-14)
    assert i == pytest.approx(ode.y[0, -1], rel=1e-9)
    # mean current: integral of expm over [0, h] / h (the same augmented form, one dimension up)
    mean_block = np.zeros((3, 3))
    mean_block[:2, :2], mean_block[:2, 2] = augmented, [i0, u]
    i_mean = expm(mean_block * h)[0, 2] / h
    friction = params.b * omega + params.mu * math.tanh(omega / params.omega_eps)
    assert tau == pytest.approx(params.kt * i_mean - friction, rel=1e-11)


def test_current_controller_is_python_controls_simulation_of_its_design():
    """Unsaturated, K(z) stepped by the kernel (motor.CurrentController.update) gives the
    output python-control's forced_response computes for the design's transfer function."""
    drive = Drive(motor1)
    controller = drive.controller
    controller.reset(0.0)
    errors = 0.02 * np.sin(0.3 * np.arange(60)) + 0.01
    v = [controller.update(e, 0.0) for e in errors]
    assert max(abs(x) for x in v) < motor1.v_max         # never saturated: K(z) itself
    response = control.forced_response(controller.design.controller, T=np.arange(60) * drive.T, U=errors)
    assert np.allclose(v, np.squeeze(response.outputs), rtol=1e-10, atol=1e-12)


def test_controller_saturates_and_keeps_the_saturated_output():
    """Anti-windup: a large error gives +-v_max, and the state remembers v_max (not the
    unsaturated value), so the next small error leaves saturation at once."""
    controller = Drive(motor1).controller
    controller.reset(0.0)
    assert controller.update(100.0, 0.0) == motor1.v_max
    assert controller.buf[kernel.CONTROLLER["u1"]] == motor1.v_max
    assert controller.update(-100.0, 0.0) == -motor1.v_max


@pytest.mark.parametrize("omega", [-0.5, -2e-3, 1e-4, 3e-3, 0.05, 2.0])
def test_lugre_steady_friction_is_the_stribeck_curve(omega):
    """At constant speed the bristles settle (the exact step takes any length) and F = sign(omega) G(omega) + sigma2 omega, with
    G = Fc + (Fs - Fc) exp(-(omega/omega_s)^2) (the paper's (3) and (5)), written here."""
    model = fr.LuGre.of_motor(motor1)
    f = fr.new_lugre(model)
    g = model.Fc + (model.Fs - model.Fc) * math.exp(-(omega / model.omega_s) ** 2)
    settle = 60.0 * g / (model.sigma0 * abs(omega))      # 60 time constants of (1): one exact step each
    z, _, _ = fr.advance(f, 0.0, omega, settle)
    z, f_end, f_mean = fr.advance(f, z, omega, settle)
    expected = math.copysign(g, omega) + model.sigma2 * omega
    assert f_end == pytest.approx(expected, rel=1e-9)
    assert f_mean == pytest.approx(expected, rel=1e-9)
    assert fr.steady_deflection(f, omega) == pytest.approx(math.copysign(g, omega) / model.sigma0, rel=1e-12)


def _splitmix64(x: int) -> int:
    """SplitMix64's output for state x (Steele, Lea, Flood 2014), in Python integers."""
    z = (x + 0x9E3779B97F4A7C15) & MASK
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
    return z ^ (z >> 31)


def test_splitmix64_gives_its_published_sequence():
    """From seed 0 the generator's first outputs are 0xe220a8397b1dcdaf, 0x6e789e6aa1b965f4,
    0x06c45d188009454f (Vigna's splitmix64.c); state k is k times the golden gamma."""
    golden = 0x9E3779B97F4A7C15
    published = [0xE220A8397B1DCDAF, 0x6E789E6AA1B965F4, 0x06C45D188009454F]
    assert [kernel.splitmix64((k * golden) & MASK) for k in range(3)] == published


@pytest.mark.parametrize("seed, instance, step", [(0, 0, 0), (11, 1, 17), (2 ** 53 - 1, 2, 10 ** 9), (7, 0, 123456)])
def test_noise_is_splitmix64_and_box_muller(seed, instance, step):
    """uniform and gaussian against a Python SplitMix64 chained over (seed, instance, step),
    the top 53 bits as (k + 1) / 2^53, and Box-Muller."""
    key = _splitmix64(_splitmix64(_splitmix64(seed) ^ instance) ^ step)
    u1 = ((key >> 11) + 1) / 2.0 ** 53
    u2 = ((_splitmix64(key) >> 11) + 1) / 2.0 ** 53
    assert uniform(seed, instance, step) == u1
    assert gaussian(seed, instance, step) == pytest.approx(math.sqrt(-2.0 * math.log(u1)) * math.cos(2 * math.pi * u2),
                                                           rel=1e-15, abs=1e-15)


def _drive_io(drive: Drive):
    """drive's context for pc_drive_io (the compiled loop's call), kept alive with it."""
    return kernel.DriveContext(*(None if b is None else kernels.address(b)
                                 for b in (drive.buf, drive._controller_buf, drive.lugre)))


@pytest.mark.parametrize("options", [{}, {"friction": "lugre", "pwm_counts": 255, "current_noise": 0.02}])
def test_drive_io_is_the_drive_step(options):
    """pc_drive_io (x = [i_ref, v_ref, omega, i_hat | tau, v, i]) steps the drive as Drive.step
    does, LuGre, PWM and noise included."""
    a, b = Drive(motor1, torque_output="mean", **options), Drive(motor1, torque_output="mean", **options)
    a.prepare_step(H)
    context = _drive_io(a)
    refusal = kernels.Refusal()
    for k in range(30):
        inputs = [0.3 * math.sin(0.2 * k), 0.0, 2.0 * math.cos(0.1 * k), 0.01 * k]
        x = np.array(inputs + [0.0] * 3)
        assert kernel.drive_io(ctypes.addressof(context), kernels.address(x), k * H, H, ctypes.byref(refusal)) == 0
        assert tuple(x[4:]) == b.step(*inputs, H)
    assert np.array_equal(a.buf, b.buf) and (a.lugre is None or np.array_equal(a.lugre, b.lugre))


@pytest.mark.parametrize("bad, index", [((0.1, 0.0, math.nan, 0.0), 0), ((math.inf, 0.0, 1.0, 0.0), 1),
                                        ((0.1, -math.inf, 1.0, 0.0), 2), ((0.1, 0.0, 1.0, math.nan), 3)])
def test_a_refused_drive_io_names_the_input_and_changes_nothing(bad, index):
    """A non-finite input: code NONFINITE_INPUT, the input's index (omega, i_ref, v_ref, i_hat)
    and value in the refusal; the drive's buffers, LuGre state and the outputs unchanged."""
    drive = Drive(motor1, friction="lugre", current_noise=0.01)
    drive.step(0.2, 0.0, 0.5, 0.0, H)
    before = drive.buf.copy(), drive._controller_buf.copy(), drive.lugre.copy()
    context = _drive_io(drive)
    refusal = kernels.Refusal()
    x = np.array(list(bad) + [7.0, 8.0, 9.0])
    code = kernel.drive_io(ctypes.addressof(context), kernels.address(x), 0.0, H, ctypes.byref(refusal))
    assert (code, refusal.code, refusal.index) == (kernel.NONFINITE_INPUT, kernel.NONFINITE_INPUT, index)
    assert np.array_equal([refusal.value], [bad[[2, 0, 1, 3][index]]], equal_nan=True)   # x's order: i_ref, v_ref, omega
    assert all(np.array_equal(b, a) for b, a in zip(before, (drive.buf, drive._controller_buf, drive.lugre)))
    assert list(x[4:]) == [7.0, 8.0, 9.0]
    with pytest.raises(kernels.Refused) as caught:
        drive.step(*bad, H)
    name = ("omega", "i_ref", "v_ref", "i_hat")[index]
    assert caught.value.variable == name and str(caught.value).startswith(f"{name} must be a finite number, got")
    assert all(np.array_equal(b, a) for b, a in zip(before, (drive.buf, drive._controller_buf, drive.lugre)))


def test_a_diverging_euler_step_is_refused_with_its_values_and_changes_nothing():
    """Euler with h > 2 L/R multiplies the current by 1 - hR/L < -1 each step: the step whose
    current overflows is refused (DIVERGED), its message names i, tau and why; the state stays."""
    params = motor1.with_(L=motor1.R * H / 100)
    drive = Drive(params, mode="voltage", method="euler")
    with pytest.raises(kernels.Refused) as caught:
        for _ in range(1000):
            before = drive.buf.copy()
            drive.step(0.0, 1.0, 0.0, 0.0, H)
    assert caught.value.code == kernel.DIVERGED and caught.value.reason == "diverged"
    assert "after this step are not finite: method 'euler' diverges" in str(caught.value)
    assert np.array_equal(drive.buf, before) and math.isfinite(drive.i)


def test_observer_io_is_the_estimate_and_a_refusal_keeps_the_state():
    """pc_observer_io (x = [v, omega | i_hat]) estimates as CurrentObserver.estimate; a NaN
    speed is refused with index 1 and the observer's buffer unchanged."""
    a, b = CurrentObserver(motor2, "dynamic"), CurrentObserver(motor2, "dynamic")
    a.prepare_step(H)
    context = kernel.ObserverContext(kernels.address(a.buf))
    refusal = kernels.Refusal()
    for k in range(10):
        x = np.array([3.0 * k, 0.5 * k, 0.0])
        assert kernel.observer_io(ctypes.addressof(context), kernels.address(x), 0.0, H, ctypes.byref(refusal)) == 0
        assert x[2] == b.estimate(3.0 * k, 0.5 * k, H)
    before = a.buf.copy()
    x = np.array([1.0, math.nan, -1.0])
    assert kernel.observer_io(ctypes.addressof(context), kernels.address(x), 0.0, H, ctypes.byref(refusal)) == 1
    assert (refusal.index, x[2]) == (1, -1.0) and np.array_equal(a.buf, before)


def test_shaft_torque_is_b2_once():
    """motor.shaft_torque and the drive's torque are B.2 (kernels/src/pc_motor.h) written out here."""
    from motor import shaft_torque

    for i, omega in ((0.3, 0.0), (-1.0, 2.5), (0.7, -0.2)):
        b2 = motor1.kt * i - motor1.b * omega - motor1.mu * math.tanh(omega / motor1.omega_eps)
        assert shaft_torque(i, omega, motor1) == pytest.approx(b2, rel=1e-15, abs=1e-17)
        drive = Drive(motor1)
        drive.reset(i, 0.0)
        assert drive.torque(omega) == pytest.approx(b2, rel=1e-15, abs=1e-17)


def test_a_copied_drive_steps_its_own_buffers():
    """The C calls hold buffer addresses: a deep copy (an FMU state) binds its own, so stepping
    the copy leaves the original alone."""
    import copy

    drive = Drive(motor1, friction="lugre")
    drive.step(0.3, 0.0, 0.5, 0.0, H)
    before = drive.buf.copy(), drive.lugre.copy()
    twin = copy.deepcopy(drive)
    twin.step(0.3, 0.0, 0.5, 0.0, H)
    assert np.array_equal(drive.buf, before[0]) and np.array_equal(drive.lugre, before[1])
    assert not np.array_equal(twin.buf, before[0])


@pytest.mark.parametrize("word", [-1.0, math.nan, 1e30])
def test_a_seed_word_outside_the_whole_numbers_draws_seed_zeros_noise(word):
    """The noise's seed is a double in the buffer (a restored FMU state writes it): outside
    [0, 2^64), where C's conversion would be undefined, the kernel takes 0."""
    voltages = []
    for seed in (word, 0.0):
        drive = Drive(motor1, current_noise=0.05)
        drive.buf[kernel.DRIVE["noise_seed"]] = seed
        voltages.append(drive.step(0.0, 0.0, 0.0, 0.0, H)[1])
    assert voltages[0] == voltages[1] and math.isfinite(voltages[0])


def test_an_observer_estimate_that_overflows_is_refused_and_not_kept():
    """v = 1e308 V on a motor with R << 1: the estimate (v - ke omega)/R overflows; the
    refusal names i_hat, its value and the time, and the observer keeps its last estimate."""
    observer = CurrentObserver(motor1.with_(R=1e-3), "static")
    kept = observer.estimate(1.0, 0.0, H)
    with pytest.raises(kernels.Refused) as caught:
        observer.estimate(1e308, 0.0, H, time=0.25)
    assert caught.value.variable == "i_hat" and caught.value.code == kernel.DIVERGED and caught.value.time == 0.25
    assert str(caught.value).startswith("the estimate i_hat = inf A at t = 0.25 s is not finite (inputs v = 1e+308 V")
    assert observer.i_hat == kept


@pytest.mark.parametrize("counts", [0, 7, 255])
def test_the_current_loop_is_its_difference_equation_and_the_pwm_rounds_only_the_applied(counts):
    """Sampled every step, the applied voltage is the controller's difference equation (K(z):
    u_k = (1 + delta) u_k-1 - delta u_k-2 + alpha e_k + beta e_k-1 + gamma e_k-2, saturated at
    v_max) computed here from its coefficients, rounded to the nearest multiple of v_max /
    counts (ties away from zero), while the recursion remembers its own unrounded u.  Catches
    the controller remembering the rounded voltage (or rounding without PWM), a dropped or
    shifted term of the recursion, and a wrong rounding."""
    drive = Drive(motor1, torque_output="mean", pwm_counts=counts)
    drive.prepare_step(H)
    c, buf = kernel.CONTROLLER, drive._controller_buf
    delta, alpha, beta, gamma, v_max = (float(buf[c[n]][0]) for n in ("delta", "alpha", "beta", "gamma", "v_max"))
    quantum = v_max / counts if counts else 0.0
    u1 = u2 = e1 = e2 = 0.0
    rounded = 0
    for k in range(60):
        i_ref, i_hat = 0.3 * math.sin(0.2 * k), 0.05 * math.cos(0.3 * k)
        _, v, _ = drive.step(i_ref, 0.0, 1.0, i_hat, H)
        e = i_ref - i_hat
        u = min(v_max, max(-v_max, (1.0 + delta) * u1 - delta * u2 + alpha * e + beta * e1 + gamma * e2))
        want = math.copysign(math.floor(abs(u) / quantum + 0.5) * quantum, u) if quantum else u
        assert v == want, k
        rounded += v != u
        u2, u1, e2, e1 = u1, u, e1, e
    assert (rounded > 30) == bool(counts)
