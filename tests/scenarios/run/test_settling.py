"""The settled steady-state error (scenarios.run.metrics.settling): synthetic errors with a known
settling time, errors that never settle, and a bench scene that settles late."""
import math

import numpy as np
import pytest

from scenarios.run.metrics import SETTLE_BAND, SETTLE_HOLD, settling

STOP, AFTER, H = 4.5, 3.0, 1e-3


def _time():
    return np.round(np.arange(0.0, STOP + AFTER + H / 2, H), 12)


def _decay(t, amplitude, tau, offset):
    """Zero before the stop's transient starts, then offset + amplitude e^(-(t - STOP)/tau)."""
    s = np.clip(t - STOP, 0.0, None)
    return offset + amplitude * np.exp(-s / tau)


def test_exponential_decay_settles_when_it_enters_the_band_for_good():
    """e_x = c + A e^(-s/τ): it enters the band around c at s = τ ln(A/band) (analytic); e_ss
    is the RMS from there on, compared with the integral of (c + A e^(-s/τ))²."""
    t = _time()
    amplitude, tau, c = 1e-3, 0.2, 3e-4
    ex, ey = _decay(t, amplitude, tau, c), np.zeros_like(t)
    settled, t_settle, mask = settling(t, ex, ey, STOP)
    expected = tau * math.log(amplitude / SETTLE_BAND)             # 0.599 s
    assert settled and t_settle == pytest.approx(expected, abs=1.5 * H)
    a, b = t_settle, AFTER
    mean_square = (c * c * (b - a) + 2 * c * amplitude * tau * (math.exp(-a / tau) - math.exp(-b / tau))
                   + amplitude ** 2 * tau / 2 * (math.exp(-2 * a / tau) - math.exp(-2 * b / tau))) / (b - a)
    assert math.sqrt(float(np.mean(ex[mask] ** 2))) == pytest.approx(math.sqrt(mean_square), rel=2e-3)


def test_dither_within_one_count_is_settled():
    """The encoder's limit cycle between two counts (±0.8 band around the final position, in
    both directions) does not stop the detection: settling time as without the dither."""
    t = _time()
    amplitude, tau = 1e-3, 0.1
    dither = 0.8 * SETTLE_BAND * np.sign(np.sin(2 * np.pi * 37.0 * t)) / math.sqrt(2)
    ex = _decay(t, amplitude, tau, 0.0) + dither
    ey = -dither
    settled, t_settle, _ = settling(t, ex, ey, STOP)
    # entering: A e^(-s/τ) + 0.8 band/√2·(1, -1) inside the band; the decay alone gives the bound
    assert settled and tau * math.log(amplitude / SETTLE_BAND) - 0.05 <= t_settle <= tau * math.log(
        amplitude / (0.2 * SETTLE_BAND))


def test_a_limit_cycle_wider_than_the_band_never_settles():
    """Stick-slip hunting of 2 bands' amplitude: not settled; e_ss over the last 0.2 s is its
    RMS (amplitude/√2 over whole periods)."""
    t = _time()
    amplitude = 2 * SETTLE_BAND
    ex = amplitude * np.sin(2 * np.pi * 10.0 * (t - STOP)) * (t >= STOP)
    settled, t_settle, mask = settling(t, ex, np.zeros_like(t), STOP)
    assert not settled and math.isnan(t_settle)
    assert math.sqrt(float(np.mean(ex[mask] ** 2))) == pytest.approx(amplitude / math.sqrt(2), rel=1e-2)


def test_a_slow_creep_is_not_settled():
    """A creep of one band per 0.2 s stays within ±0.5 band of the mean of any 0.2 s window
    (a window-local stillness test would call it settled), but it is within the band of its
    final position only for the last (band + 0.1 s·rate)/rate = 0.3 s < SETTLE_HOLD."""
    t = _time()
    rate = SETTLE_BAND / 0.2                                        # m/s
    ex = rate * np.clip(t - STOP, 0.0, None)
    settled, t_settle, _ = settling(t, ex, np.zeros_like(t), STOP)
    assert not settled and math.isnan(t_settle)


def test_settling_too_close_to_the_end_of_the_run_does_not_count():
    """Entering the band 0.1 s short of SETTLE_HOLD before the run's end: not settled; 0.1 s
    earlier than that: settled."""
    t = _time()
    tau = 0.1
    for margin, expected in ((-0.1, False), (0.1, True)):
        enter = AFTER - SETTLE_HOLD - margin
        amplitude = SETTLE_BAND * math.exp(enter / tau)
        ex = _decay(t, amplitude, tau, 0.0)
        assert settling(t, ex, np.zeros_like(t), STOP)[0] is expected, margin


def test_bench_triangle_PDMDq_settles_late():
    """The late settler of the 16 bench scenes: 0.47 mm 1 s after the stop (the earlier e_ss),
    settled (within one count) about 1.9 s after it at a few µm."""
    from scenarios.run.runner import run_scene

    m = run_scene("bench_triangle_PDMDq", mode="compiled", plots=False).metrics
    assert m["settled"] and 1.5 < m["t_settle_s"] < 2.5
    assert m["e_ss_1s_mm"] == pytest.approx(0.4704, rel=1e-3)
    assert m["e_ss_mm"] < 0.03 < 0.4 < m["e_ss_1s_mm"]
