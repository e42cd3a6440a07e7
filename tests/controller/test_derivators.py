"""Tests of controller.derivators against the thesis' derivator (7.2.3) and its design."""

import numpy as np
import pytest
from scipy import signal

from controller.derivators import Derivator, bessel_lowpass_sos, dc_group_delay

T = 1e-3
VELOCITY_FILTER_ORDER, ACCELERATION_FILTER_ORDER = 2, 8
"""Thesis 7.2.3: 2nd-order Bessel for velocity, 8th-order for acceleration."""
CUTOFF_PAIRS = [(100.0, 40.0), (60.0, 30.0), (150.0, 60.0)]
SETTLED_FROM = {(100.0, 40.0): 150, (60.0, 30.0): 250, (150.0, 60.0): 150}
"""First sample at which the transient from rest is below 1e-9 (measured: 129 for the defaults)."""


def analog_bessel_on_unit_circle(order, fc, f):
    """Independent reference: analog Bessel with -3 dB at the prewarped fc, at the warped frequencies."""
    prewarped = 2 / T * np.tan(np.pi * fc * T)
    zeros, poles, gain = signal.bessel(order, prewarped, analog=True, norm="mag", output="zpk")
    warped = 2 / T * np.tan(np.pi * np.asarray(f) * T)
    return signal.freqs_zpk(zeros, poles, gain, worN=warped)[1]


def expected_derivator_response(fc_vel, fc_acc, f):
    """(1 - z^-1)/T F_v and ((1 - z^-1)/T)^2 F_v F_a at z = exp(j 2 pi f T), from the prototypes."""
    difference = (1 - np.exp(-2j * np.pi * np.asarray(f) * T)) / T
    velocity = difference * analog_bessel_on_unit_circle(VELOCITY_FILTER_ORDER, fc_vel, f)
    return velocity, velocity * difference * analog_bessel_on_unit_circle(ACCELERATION_FILTER_ORDER, fc_acc, f)


def run(derivator, q):
    """Reset at q[0] and step through the samples q (shape samples x channels)."""
    derivator.reset(q[0])
    estimates = np.array([np.stack(derivator.step(qk)) for qk in q])
    return estimates[:, 0, :], estimates[:, 1, :]


@pytest.mark.parametrize("order, fc", [(2, 100.0), (8, 40.0), (2, 60.0), (8, 60.0), (8, 200.0)])
def test_designed_low_pass_is_the_prewarped_bilinear_bessel(order, fc):
    """Catches the derivator's filter design departing from the prewarped bilinear Bessel (response off the
    analog one, -3 dB not at fc, DC gain not 1, an unstable pole)."""
    sos = bessel_lowpass_sos(order, fc, T)
    f = np.linspace(0.0, 450.0, 901)
    _, response = signal.sosfreqz(sos, worN=2 * np.pi * f * T)
    assert np.max(np.abs(response - analog_bessel_on_unit_circle(order, fc, f))) < 1e-9
    assert abs(abs(signal.sosfreqz(sos, worN=[2 * np.pi * fc * T])[1][0]) - np.sqrt(0.5)) < 1e-9
    np.testing.assert_allclose(sos[:, :3].sum(axis=1), sos[:, 3:].sum(axis=1), rtol=1e-14)
    poles = signal.sos2zpk(sos)[1]
    assert len(poles) == order and np.all(np.abs(poles) < 1)


def test_cutoff_outside_nyquist_is_rejected():
    """Catches a derivator designed with a cut-off above Nyquist instead of refusing it."""
    with pytest.raises(ValueError, match="cut-off"):
        Derivator(fc_vel=600.0)


@pytest.mark.parametrize("fc_vel, fc_acc", CUTOFF_PAIRS)
def test_sinusoid_response_matches_designed_filters(fc_vel, fc_acc):
    """Catches a derivator whose gain or phase at any frequency differs from its designed filters."""
    derivator = Derivator(fc_vel, fc_acc, T)
    frequencies = np.array([1.0, 5.0, 11.0, 40.0, 100.0, 250.0])
    amplitudes = np.array([0.5, 2.0])
    k = np.arange(3000)
    settled = slice(1000, None)
    expected_velocity, expected_acceleration = expected_derivator_response(fc_vel, fc_acc, frequencies)
    for f, h_velocity, h_acceleration in zip(frequencies, expected_velocity, expected_acceleration):
        phase = 2 * np.pi * f * k * T
        velocity, acceleration = run(derivator, np.sin(phase)[:, None] * amplitudes)
        basis = np.column_stack([np.sin(phase), np.cos(phase)])[settled]
        for channel, amplitude in enumerate(amplitudes):
            for estimate, expected, power in ((velocity, h_velocity, 1), (acceleration, h_acceleration, 2)):
                coefficients = np.linalg.lstsq(basis, estimate[settled, channel] / amplitude, rcond=None)[0]
                measured = coefficients[0] + 1j * coefficients[1]
                assert abs(measured - expected) < 1e-8 * (2 * np.pi * f) ** power, (f, channel, power)
    velocity, acceleration = derivator.frequency_response(frequencies)
    np.testing.assert_allclose(velocity, expected_velocity, rtol=1e-9)
    np.testing.assert_allclose(acceleration, expected_acceleration, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("fc_vel, fc_acc", CUTOFF_PAIRS)
def test_ramp_velocity_exact_after_transient(fc_vel, fc_acc):
    """Catches a derivator whose velocity of a ramp is not exact once settled (a wrong DC gain)."""
    t = np.arange(1000) * T
    slopes = np.array([2.7, -0.4])
    q = np.array([1.3, -2.2]) + t[:, None] * slopes
    velocity, acceleration = run(Derivator(fc_vel, fc_acc, T), q)
    after = SETTLED_FROM[(fc_vel, fc_acc)]
    assert np.all(np.abs(velocity[after:] - slopes) <= 1e-9 * np.abs(slopes))
    assert np.all(np.abs(acceleration[after:]) <= 1e-9 * np.abs(slopes))
    assert np.any(np.abs(velocity[:after] - slopes) > 1e-3), "a transient was expected from the start at rest"


@pytest.mark.parametrize("fc_vel, fc_acc", CUTOFF_PAIRS)
def test_parabola_acceleration_exact_after_transient(fc_vel, fc_acc):
    """Catches a derivator whose acceleration of a parabola is not exact once settled."""
    derivator = Derivator(fc_vel, fc_acc, T)
    t = np.arange(1000) * T
    initial_velocity, curvature = np.array([0.8, -1.5]), np.array([7.3, -12.0])
    q = 0.4 + initial_velocity * t[:, None] + 0.5 * curvature * t[:, None] ** 2
    velocity, acceleration = run(derivator, q)
    after = SETTLED_FROM[(fc_vel, fc_acc)]
    assert np.all(np.abs(acceleration[after:] - curvature) <= 1e-9 * np.abs(curvature))
    delayed_velocity = initial_velocity + curvature * (t[:, None] - derivator.velocity_delay)
    assert np.all(np.abs(velocity[after:] - delayed_velocity[after:]) <= 1e-9 * np.abs(curvature))


def test_cubic_acceleration_is_delayed_by_acceleration_delay():
    """Catches a stated acceleration delay other than the filters' true one."""
    derivator = Derivator()
    t = np.arange(1000) * T
    jerk = np.array([11.0, -3.0])
    velocity, acceleration = run(derivator, jerk * t[:, None] ** 3 / 6)
    delayed_acceleration = jerk * (t[:, None] - derivator.acceleration_delay)
    assert np.all(np.abs(acceleration[150:] - delayed_acceleration[150:]) <= 1e-9 * np.abs(jerk))


def test_delays_are_the_dc_group_delays_of_the_chains():
    """Catches velocity or acceleration delays that are not the chains' DC group delays."""
    derivator = Derivator()
    small = 0.01
    velocity, acceleration = derivator.frequency_response([small])
    omega = 2 * np.pi * small
    assert derivator.velocity_delay == pytest.approx(-np.angle(velocity[0] / (1j * omega)) / omega, rel=1e-6)
    assert derivator.acceleration_delay == pytest.approx(-np.angle(acceleration[0] / -(omega**2)) / omega, rel=1e-6)
    sos = derivator.acceleration_sos
    assert dc_group_delay(sos, T) == pytest.approx(signal.group_delay(signal.sos2tf(sos), w=[1e-4])[1][0] * T, rel=1e-6)


def test_reset_starts_at_rest_without_transient():
    """Catches a reset that does not start the filters at rest (a start-up transient)."""
    q0 = np.array([1.2, -2.5])
    velocity, acceleration = run(Derivator(), np.tile(q0, (300, 1)))
    assert np.max(np.abs(velocity)) < 1e-9
    assert np.max(np.abs(acceleration)) < 1e-9


def test_step_before_reset_is_an_error():
    """Catches a derivator that steps from an uninitialised state instead of refusing."""
    with pytest.raises(RuntimeError, match="reset"):
        Derivator().step([0.0, 0.0])


def test_step_values_are_the_estimates_of_step():
    """step_values (the FMU's path: one list) gives step's velocities then accelerations, bit for
    bit, advancing the state the same way."""
    listed, arrays = Derivator(30.0, 20.0, 1e-3), Derivator(30.0, 20.0, 1e-3)
    listed.reset([0.1, -0.2])
    arrays.reset([0.1, -0.2])
    for k in range(200):
        q = (0.1 + 0.3 * np.sin(0.02 * k), -0.2 + 0.1 * k * 1e-3)
        dq, ddq = arrays.step(q)
        assert listed.step_values(q) == [*dq.tolist(), *ddq.tolist()]
