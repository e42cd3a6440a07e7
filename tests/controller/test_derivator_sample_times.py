"""The derivator (controller/derivators.py, kernels/src/derivator.c) at sample times other than
1 ms: its filters against the analog Bessel prototype prewarped at that T, its chain against
scipy's filtering of the same samples, its delays and the exact derivatives of a polynomial."""

import numpy as np
import pytest
from scipy import signal

from controller.derivators import Derivator, bessel_lowpass_sos, dc_group_delay

SAMPLE_TIMES = [2.5e-4, 2e-3]


@pytest.mark.parametrize("T", SAMPLE_TIMES)
@pytest.mark.parametrize("order, fc", [(2, 100.0), (8, 40.0)])
def test_the_filter_at_another_sample_time_is_the_bessel_prewarped_at_that_time(T, order, fc):
    """Catches a design that prewarps, maps (bilinear) or checks the cut-off with 1 ms instead of
    T, or whose DC gain is not 1 at that T."""
    sos = bessel_lowpass_sos(order, fc, T)
    prewarped = 2 / T * np.tan(np.pi * fc * T)
    zeros, poles, gain = signal.bessel(order, prewarped, analog=True, norm="mag", output="zpk")
    f = np.linspace(0.0, 0.45 / T, 400)
    _, response = signal.sosfreqz(sos, worN=2 * np.pi * f * T)
    analog = signal.freqs_zpk(zeros, poles, gain, worN=2 / T * np.tan(np.pi * f * T))[1]
    assert np.max(np.abs(response - analog)) < 1e-9
    assert abs(abs(signal.sosfreqz(sos, worN=[2 * np.pi * fc * T])[1][0]) - np.sqrt(0.5)) < 1e-9
    np.testing.assert_allclose(sos[:, :3].sum(axis=1), sos[:, 3:].sum(axis=1), rtol=1e-14)
    w = 1e-4                                                      # rad/sample: the phase is -delay w + O(w^3)
    delay = -np.angle(signal.sosfreqz(sos, worN=[w])[1][0]) / w * T
    assert dc_group_delay(sos, T) == pytest.approx(delay, rel=1e-6)
    with pytest.raises(ValueError, match=rf"cut-off {0.5 / T} Hz must lie in \(0, {0.5 / T}\) Hz for T = {T} s"):
        bessel_lowpass_sos(order, 0.5 / T, T)


@pytest.mark.parametrize("T", SAMPLE_TIMES)
def test_the_chain_at_another_sample_time_is_scipys_filtering(T):
    """(1 - z^-1)/T, F_v, (1 - z^-1)/T, F_a by scipy's lfilter/sosfilt from rest at q[0], two
    channels.  Catches a difference divided by 1 ms, a state-space chain built for another T,
    or a rest state that is not the rest at q[0] for that T."""
    derivator = Derivator(80.0, 30.0, T)
    rng = np.random.default_rng(5)
    q = np.cumsum(rng.normal(0.0, 1e-3, (300, 2)), axis=0) + [0.2, -0.7]
    derivator.reset(q[0])
    estimates = np.array([np.stack(derivator.step(sample)) for sample in q])
    difference = signal.lfilter([1.0 / T, -1.0 / T], [1.0], q - q[0], axis=0)
    velocity = signal.sosfilt(derivator.velocity_sos, difference, axis=0)
    acceleration = signal.sosfilt(derivator.acceleration_sos, signal.lfilter([1.0 / T, -1.0 / T], [1.0], velocity,
                                                                             axis=0), axis=0)
    scale = np.max(np.abs(velocity)), np.max(np.abs(acceleration))
    assert np.max(np.abs(estimates[:, 0] - velocity)) < 1e-10 * scale[0]
    assert np.max(np.abs(estimates[:, 1] - acceleration)) < 1e-9 * scale[1]


@pytest.mark.parametrize("T", SAMPLE_TIMES)
def test_the_delays_at_another_sample_time_give_a_polynomials_derivatives(T):
    """Catches delays computed with 1 ms instead of T (or half a sample off): a parabola's
    velocity after the transient is dq/dt at t - velocity_delay and a cubic's acceleration
    d2q/dt2 at t - acceleration_delay, the delays being T/2 + the velocity filter's, and T +
    both filters' (difference, filters) at that T."""
    derivator = Derivator(100.0, 40.0, T)
    vel_filter = dc_group_delay(derivator.velocity_sos, T)
    assert derivator.velocity_delay == T / 2 + vel_filter
    assert derivator.acceleration_delay == T + vel_filter + dc_group_delay(derivator.acceleration_sos, T)
    n = int(round(0.6 / T))
    t = np.arange(n) * T
    late = slice(n // 3, None)
    c0, c1, c2, c3 = 0.4, 1.5, -2.0, 0.7
    for q, check in ((c0 + c1 * t + c2 * t ** 2, "velocity"), (c0 + c1 * t + c2 * t ** 2 + c3 * t ** 3, "acceleration")):
        derivator.reset([q[0]])
        v, a = np.array([derivator.step([sample]) for sample in q])[:, :, 0].T
        if check == "velocity":
            np.testing.assert_allclose(v[late], c1 + 2 * c2 * (t[late] - derivator.velocity_delay), rtol=0, atol=1e-8)
        else:
            np.testing.assert_allclose(a[late], 2 * c2 + 6 * c3 * (t[late] - derivator.acceleration_delay),
                                       rtol=0, atol=1e-6)


@pytest.mark.parametrize("fc_vel, fc_acc, T", [(30.0, 7.0, 1e-3), (70.0, 40.0, 2e-3)])
def test_a_derivators_filters_are_the_designs_of_its_own_cutoffs_and_sample_time(fc_vel, fc_acc, T):
    """The velocity filter is the order-2 Bessel design at (fc_vel, T), the acceleration filter
    the order-8 one at (fc_acc, T), bit for bit, and the delays follow from them (the
    buffer's sections read back the same).  At 100 Hz and 1 ms the design is symmetric in
    fc and T to the last bit, so cut-offs and times off the defaults.  Catches the cut-off
    and the sample time passed in each other's place, or one filter's cut-off in the other's."""
    d = Derivator(fc_vel=fc_vel, fc_acc=fc_acc, T=T)
    velocity, acceleration = bessel_lowpass_sos(2, fc_vel, T), bessel_lowpass_sos(8, fc_acc, T)
    assert np.array_equal(d.velocity_sos, velocity) and np.array_equal(d.acceleration_sos, acceleration)
    assert d.velocity_delay == T / 2 + dc_group_delay(velocity, T)
    assert d.acceleration_delay == T + dc_group_delay(velocity, T) + dc_group_delay(acceleration, T)
