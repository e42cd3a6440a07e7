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
    the file is written, its missing folders made.  Catches an inverted magnitude axis, and the
    folder made without its parents (sibling of seed 4201 [196])."""
    import matplotlib.pyplot as plt

    before = set(plt.get_fignums())
    derivator = Derivator()
    figures.plot_bode(derivator, tmp_path / "new" / "figures" / "bode.png")
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
        assert (tmp_path / "new" / "figures" / "bode.png").stat().st_size > 0
    finally:
        plt.close(figure)


def test_the_bode_plot_spans_the_published_decades_and_marks_5_and_11_hz(tmp_path):
    """docs/derivators.md's figure (docs/derivators_bode.png, written by this function with
    ``--docs``) runs from 0.1 Hz to just below the Nyquist frequency 0.5 / T (where the velocity
    estimate's magnitude is zero, -inf dB), every plotted value finite, both panels on the same
    frequencies; "the dotted lines mark 5 Hz and 11 Hz" on both panels, its title states T.
    Catches the plot started another decade down (seed 3901 [290]), Nyquist itself plotted, a
    marker moved or dropped, and the phase on other frequencies."""
    import matplotlib.pyplot as plt

    before = set(plt.get_fignums())
    derivator = Derivator(50.0, 20.0)
    figures.plot_bode(derivator, tmp_path / "bode.png")
    (number,) = set(plt.get_fignums()) - before
    figure = plt.figure(number)
    try:
        magnitude, phase = figure.axes
        curves = magnitude.lines[:2] + phase.lines[:2]
        f = np.asarray(curves[0].get_xdata())
        assert f[0] == pytest.approx(0.1, rel=1e-12) and f[-1] < (1 - 1e-6) * 0.5 / derivator.T     # Nyquist left out
        assert f[-1] > 0.98 * 0.5 / derivator.T and np.all(np.diff(f) > 0)
        for line in curves:
            assert np.array_equal(line.get_xdata(), f) and np.all(np.isfinite(line.get_ydata()))
        for axes in (magnitude, phase):
            dotted = sorted(line.get_xdata()[0] for line in axes.lines[2:] if line.get_linestyle() == ":")
            assert dotted == [5.0, 11.0]
        assert magnitude.get_title().startswith(f"Derivators at T = {derivator.T * 1e3:g} ms")
    finally:
        plt.close(figure)


class _Scripted:
    """A derivator answering scripted estimates (the transient's ends known) and recording what
    it was fed."""

    T = 1e-3

    def __init__(self):
        self.fed, self.started = [], None

    def reset(self, values):
        self.started = list(values)

    def step(self, values):
        n = len(self.fed)
        self.fed.append(list(values))
        tolerance = figures.TRANSIENT_TOLERANCE
        velocity = 2.7 + (1.0 if n < 7 else 0.0)
        # The ramp's acceleration is exactly the tolerance (not more: no miss) from sample 4 to 9.
        ramp_acceleration = 1.0 if n < 4 else (tolerance * 2.7 if n < 10 else 0.0)
        parabola_acceleration = 7.3 * (1.0 + 2 * tolerance) if n < 12 else 7.3
        return np.array([velocity, 0.0]), np.array([ramp_acceleration, parabola_acceleration])


def test_the_transient_lasts_until_the_last_sample_missing_by_more_than_the_tolerance():
    """transient_samples feeds the ramp 1.3 + 2.7 t and the parabola 0.4 + 7.3 t²/2 at t = n T
    from a reset at their first values, and counts the samples up to the last one whose ramp
    velocity, ramp acceleration (against the slope) or parabola acceleration misses by more than
    1e-9 relative: a miss of exactly the tolerance is none, one of twice it is.  Seed 4101 [204]'s
    sibling (the mutant itself is equivalent: |v - 2.7| near 2.7e-9 is a whole number of 2^-51,
    which 2.7e-9 is not, so the velocity can never tie; the acceleration can)."""
    derivator = _Scripted()
    assert figures.transient_samples(derivator, horizon=50) == (7, 4, 12)
    assert derivator.started == [1.3, 0.4] and len(derivator.fed) == 50
    t = np.arange(50) * 1e-3
    assert np.allclose(derivator.fed, np.column_stack([1.3 + 2.7 * t, 0.4 + 3.65 * t ** 2]), rtol=1e-15, atol=1e-15)
