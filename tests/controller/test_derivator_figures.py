"""The derivators' figures of merit (scenarios/examples/plot_derivators.py, quoted in
docs/derivators.md) at a sample time of 2 ms and cut-offs off the defaults, against
computations that share no code with it: the filters as scipy's transfer-function Bessel
designs evaluated by ``freqz`` (the product: second-order sections by ``sosfreqz``), the
position loop's phase margin by python-control's ``margin`` of the same loop built as a
discrete transfer function, and the continuous loop's margin by root finding (issue 31,
patterns 1 and 2)."""
from __future__ import annotations

import math

import control
import numpy as np
import pytest
from scipy import optimize, signal

from controller.derivators import Derivator
from scenarios.examples.plot_derivators import ideal_phase_margin, lag_degrees, phase_margin

T = 2e-3
FC_VEL, FC_ACC = 60.0, 25.0


def _filters():
    b_v, a_v = signal.bessel(2, FC_VEL, norm="mag", fs=1.0 / T)
    b_a, a_a = signal.bessel(8, FC_ACC, norm="mag", fs=1.0 / T)
    return (b_v, a_v), (b_a, a_a)


def test_the_phase_lags_are_those_of_scipys_bessel_filters_on_backward_differences():
    """velocity = (1 - z^-1)/T F_v(z), acceleration = (1 - z^-1)/T F_a(z) velocity; the lag is
    the phase behind j omega and -omega^2.  Catches the two lags swapped, a sign, the ideal
    derivative's factor wrong, a lag at T = 1 ms."""
    f = np.array([1.0, 5.0, 11.0, 40.0])
    (b_v, a_v), (b_a, a_a) = _filters()
    w = 2 * np.pi * f * T
    _, f_v = signal.freqz(b_v, a_v, worN=w)
    _, f_a = signal.freqz(b_a, a_a, worN=w)
    difference = (1 - np.exp(-1j * w)) / T
    velocity = difference * f_v
    acceleration = difference * f_a * velocity
    omega = 2 * np.pi * f
    expected_v = -np.degrees(np.angle(velocity / (1j * omega)))
    expected_a = -np.degrees(np.angle(acceleration / -(omega ** 2)))
    lag_v, lag_a = lag_degrees(Derivator(FC_VEL, FC_ACC, T), f)
    assert lag_v == pytest.approx(expected_v, rel=1e-9, abs=1e-9)
    assert lag_a == pytest.approx(expected_a, rel=1e-9, abs=1e-9)
    assert np.all(lag_a[:3] > lag_v[:3]) and np.all(lag_v > 0.0)         # (at 40 Hz the acceleration wraps)
    # at low frequency the lag is the delay: half a sample of the difference and the filter's
    group = -np.gradient(np.unwrap(np.angle(f_v)), w)[0] * T   # the filter's group delay [s] at 1 Hz
    assert lag_v[0] == pytest.approx(360.0 * 1.0 * (T / 2 + group), rel=2e-3)


@pytest.mark.parametrize("lam", [35.0, 70.0])
def test_the_continuous_loops_margin_is_where_its_gain_crosses_one(lam):
    """(lam^2 + 2 lam s)/s^2: the crossover by root finding, the margin 180 + its phase."""
    def gain(w):
        return abs((lam ** 2 + 2j * lam * w) / (1j * w) ** 2) - 1.0

    crossover = optimize.brentq(gain, 0.1 * lam, 10.0 * lam, xtol=1e-14)
    loop = (lam ** 2 + 2j * lam * crossover) / (1j * crossover) ** 2
    assert ideal_phase_margin(lam) == pytest.approx(180.0 + math.degrees(np.angle(loop)), rel=1e-10)


def test_the_sampled_loops_margin_is_python_controls_margin_of_the_same_loop():
    """L(z) = (lam^2 + 2 lam H_v(z)) T^2 (z + 1) / (2 (z - 1)^2) at T = 2 ms, with one more
    sample of delay; python-control's phase margin and crossover.  Catches the derivator's
    velocity left out of the loop, the hold's (z + 1)/2 or the delay dropped, the crossover
    taken where the gain is above one."""
    lam, delay = 60.0, 1
    (b_v, a_v), _ = _filters()
    z = control.tf([1.0, 0.0], [1.0], T)
    filter_v = control.tf(b_v, a_v, dt=T)
    velocity = filter_v * (z - 1) / (T * z)
    loop = (lam ** 2 + 2 * lam * velocity) * T ** 2 * (z + 1) / (2 * (z - 1) ** 2) / z ** delay
    _, pm, _, wc = control.margin(loop)
    margin, crossover = phase_margin(Derivator(FC_VEL, FC_ACC, T), lam, extra_delay_steps=delay)
    assert crossover == pytest.approx(wc / (2 * math.pi), rel=1e-4)
    assert margin == pytest.approx(pm, abs=0.02)
    without = phase_margin(Derivator(FC_VEL, FC_ACC, T), lam)[0]
    assert without - margin == pytest.approx(math.degrees(wc * T), abs=0.05)   # one sample: omega T
