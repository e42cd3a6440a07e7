"""The derivator's C cascade (kernels/src/derivator.c: the two backward differences and the
Bessel low-passes' second-order sections in direct form II transposed) against formulations it
shares no code with: scipy's own digital Bessel design evaluated from its zeros, poles and gain;
the chain's state-space model multiplied out by numpy; and per-channel runs (the kernel steps
two channels side by side)."""
import numpy as np
import pytest
from scipy import signal

from controller import fastderivator
from controller.derivators import ACCELERATION_FILTER_ORDER, VELOCITY_FILTER_ORDER, Derivator, _differentiator_ss

T = 1e-3
#: Samples of an impulse response: the slowest pole (F_a's, radius 0.81 at 40 Hz, 0.87 at 25 Hz)
#: has decayed below 1e-150 by then.
SAMPLES = 3000


def impulse_responses(derivator, channels=1):
    """The velocity and acceleration estimates of a unit impulse from rest at 0."""
    derivator.reset(np.zeros(channels))
    q = np.zeros((SAMPLES, channels))
    q[1] = 1.0
    steps = [derivator.step(sample) for sample in q]
    return np.array([v[0] for v, _ in steps]), np.array([a[0] for _, a in steps])


def zpk_responses(fc_vel, fc_acc, omega):
    """The chain's frequency responses from scipy's digital Bessel designs (prewarped
    bilinear, -3 dB at fc) as zeros, poles and gain, and the differences (1 - e^-jw)/T."""
    difference = (1.0 - np.exp(-1j * omega)) / T
    _, velocity_filter = signal.freqz_zpk(*signal.bessel(VELOCITY_FILTER_ORDER, fc_vel, norm="mag", output="zpk",
                                                        fs=1.0 / T), worN=omega)
    _, acceleration_filter = signal.freqz_zpk(*signal.bessel(ACCELERATION_FILTER_ORDER, fc_acc, norm="mag",
                                                            output="zpk", fs=1.0 / T), worN=omega)
    velocity = difference * velocity_filter
    return velocity, difference * acceleration_filter * velocity


@pytest.mark.parametrize("fc_vel, fc_acc", [(100.0, 40.0), (60.0, 25.0), (200.0, 80.0)])
def test_the_cascade_has_the_transfer_functions_of_scipys_zpk_design(fc_vel, fc_acc):
    """The transform of the kernel's impulse responses is scipy's zpk design times the
    differences at every frequency, to rounding.  Catches a wrong coefficient, a section's
    update in the wrong order (s1 read after it was replaced), a swapped b1/b2 or a1/a2, a
    difference of the wrong sign or rate, a section skipped or run twice."""
    velocity, acceleration = impulse_responses(Derivator(fc_vel, fc_acc, T))
    omega = np.linspace(0.01, np.pi - 0.01, 61)
    transform = np.exp(-1j * np.outer(omega, np.arange(SAMPLES) - 1))   # the impulse at sample 1
    expected_velocity, expected_acceleration = zpk_responses(fc_vel, fc_acc, omega)
    for got, expected in ((transform @ velocity, expected_velocity), (transform @ acceleration, expected_acceleration)):
        assert np.abs(got - expected).max() <= 1e-13 * np.abs(expected).max()


def test_the_cascade_is_the_chain_state_space_word_for_word():
    """Random angles on two channels: the estimates and every state word after every step are
    those of the chain's state-space model (controller.derivators._differentiator_ss, states in
    the kernel's order) multiplied out by numpy, to rounding.  Catches state words in another
    order than the documented one (a saved FMU state read differently), s0 and s1 swapped, a
    channel's words written into the other's."""
    derivator = Derivator()
    velocity_chain = _differentiator_ss(derivator.velocity_sos, T)
    a, b, c_acc, d_acc = _differentiator_ss(derivator.acceleration_sos, T, upstream=velocity_chain)
    c_vel = np.zeros_like(c_acc)
    c_vel[:, :velocity_chain[0].shape[0]] = velocity_chain[2]
    rng = np.random.default_rng(38)
    q = np.cumsum(rng.normal(0.0, 0.01, (300, 2)), axis=0) + [0.4, -1.1]
    derivator.reset(q[0])
    x = np.zeros((a.shape[0], 2))
    x[0] = q[0]
    for sample in q:
        dq, ddq = derivator.step(sample)
        expected_dq, expected_ddq = (c_vel @ x + velocity_chain[3] * sample)[0], (c_acc @ x + d_acc * sample)[0]
        x = a @ x + b * sample
        _, state = fastderivator.views(derivator.buf)
        np.testing.assert_allclose(dq, expected_dq, rtol=0, atol=1e-12 * max(1.0, np.abs(expected_dq).max()))
        np.testing.assert_allclose(ddq, expected_ddq, rtol=0, atol=1e-11 * max(1.0, np.abs(expected_ddq).max()))
        np.testing.assert_allclose(state[:-1], x, rtol=0, atol=1e-12 * max(1.0, np.abs(x).max()))
        assert state[-1].tolist() == sample.tolist()


@pytest.mark.parametrize("channels", [3, 4])
def test_channels_side_by_side_are_each_channel_alone(channels):
    """Three channels (the third paired with itself) and four (two pairs side by side, the
    second at words 2 and 3): each channel's estimates are, bit for bit, those of a one-channel
    derivator fed that channel alone.  Catches the lanes of a channel pair mixed up, the odd
    channel's words written twice with different values, a channel reading another's state, a
    second pair read at the first pair's words."""
    rng = np.random.default_rng(3)
    q = np.cumsum(rng.normal(0.0, 0.02, (200, channels)), axis=0)
    together = Derivator()
    together.reset(q[0])
    joint = [together.step(sample) for sample in q]
    for ch in range(channels):
        alone = Derivator()
        alone.reset(q[0, ch:ch + 1])
        single = [alone.step(sample[ch:ch + 1]) for sample in q]
        assert [v[ch] for v, _ in joint] == [v[0] for v, _ in single]
        assert [a[ch] for _, a in joint] == [a[0] for _, a in single]


def test_at_rest_a_constant_angle_gives_exactly_zero():
    """Reset at q0 (or started at the first sample) and held there: both estimates exactly 0
    at every sample.  Catches a rest state that leaves the filters a transient."""
    for start in ("reset", "first sample"):
        derivator = Derivator()
        if start == "reset":
            derivator.reset([0.7, -2.3])
        else:
            derivator.start_at_first_sample(2)
        for _ in range(50):
            dq, ddq = derivator.step([0.7, -2.3])
            assert dq.tolist() == [0.0, 0.0] and ddq.tolist() == [0.0, 0.0]


@pytest.mark.parametrize("channels", [1, 2, 3])
def test_a_non_finite_estimate_leaves_every_channels_state(channels):
    """One channel's estimate overflows (a huge rate and a large jump on the last channel): the
    estimates come out, and the state of every channel, the last angles and the start flag stay.
    Catches a step that commits a pair's next state before every channel's estimates are
    known to be finite (one pair kept in place, several through the scratch)."""
    derivator = Derivator()
    derivator.reset(np.zeros(channels))
    derivator.step(np.full(channels, 0.01))
    derivator.buf[fastderivator.V_RATE] = 1e300
    saved = derivator.buf.copy()
    q = np.full(channels, 0.01)
    q[-1] = 1e10
    dq, _ = derivator.step(q)
    assert np.isinf(dq[-1])
    np.testing.assert_array_equal(derivator.buf, saved)
