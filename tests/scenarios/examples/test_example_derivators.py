"""The derivator figures' quantisation noise and Bode plot (scenarios/examples/plot_derivators.py),
against the encoder of SYSTEM.md (20000 counts a turn) and the uniform-quantisation model."""
from __future__ import annotations

import math

import numpy as np
import pytest

from controller.derivators import Derivator
from scenarios.examples import plot_derivators as figures

#: SYSTEM.md section 3: 20000 counts per turn.
STEP = 2 * math.pi / 20000


def test_the_quantisation_noise_is_that_of_one_count_rounding():
    """Rounding to one count leaves a uniform error of variance step²/12; on a sine that crosses
    several counts a sample, the bare backward difference's noise is sqrt(2 step²/12) / T (two
    independent errors) to 5 %, and the derivators' noise is the white model's (impulse-response
    gains) to 20 %.  Catches the angles rounded to radians instead of counts."""
    assert figures.ENCODER_STEP == pytest.approx(STEP, rel=1e-15)
    derivator = Derivator()
    (velocity, acceleration), bare = figures.simulated_quantisation_noise(derivator, seconds=4.0)
    assert bare == pytest.approx(math.sqrt(2.0 / 12.0) * STEP / derivator.T, rel=0.05)
    gain_v, gain_a = figures.impulse_noise_gains(derivator)
    white = STEP / math.sqrt(12.0)
    assert velocity == pytest.approx(white * gain_v, rel=0.2)
    assert acceleration == pytest.approx(white * gain_a, rel=0.2)


def test_the_bode_plot_shows_each_estimate_over_the_ideal_derivative_on_rising_axes(tmp_path):
    """The magnitude panel's curves are 20 log10(|H| / ω^n) of the derivator's own frequency
    response, its limits rise (bottom below -40 dB) and hold the curves' pass band (0 dB at 1 Hz);
    the file is written.  Catches an inverted magnitude axis."""
    import matplotlib.pyplot as plt

    before = set(plt.get_fignums())
    derivator = Derivator()
    figures.plot_bode(derivator, tmp_path / "bode.png")
    (number,) = set(plt.get_fignums()) - before
    figure = plt.figure(number)
    try:
        magnitude, phase = figure.axes
        bottom, top = magnitude.get_ylim()
        assert bottom < -40.0 < 0.0 < top          # rising, down to the stop band, the pass band inside
        for n, line in enumerate(magnitude.lines[:2], start=1):
            f = np.asarray(line.get_xdata())
            response = derivator.frequency_response(f)[n - 1]
            expected = 20 * np.log10(np.abs(response) / (2 * np.pi * f) ** n)
            assert np.allclose(line.get_ydata(), expected, rtol=0, atol=1e-9)
            at_1hz = np.interp(1.0, f, line.get_ydata())
            assert abs(at_1hz) < 0.1 and magnitude.get_ylim()[0] < at_1hz < magnitude.get_ylim()[1]
        assert (tmp_path / "bode.png").stat().st_size > 0
    finally:
        plt.close(figure)
