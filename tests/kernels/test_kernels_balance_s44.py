"""The balance controller's C sample (kernels/src/balance.c) on the words its sizes leave out
and at the ends of the route's smooth steps (session 44, training 4411/4412 generalised).

A design of n < N_MAX kept states and ny < NY_MAX measurements uses only the first n (ny)
rows and columns of its fixed-size matrices and estimate: every other word may hold anything
(here NaN, which would poison any result it entered) and is neither read nor written.  The
smooth step (7.27) is 0 at and before its window's start and 1 at and after its end, whatever
polynomial the buffer holds between."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from controller import fastbalance as fb
from tests.kernels.test_kernels_wheeled import _buffer

N_MAX, NY_MAX = fb.N_MAX, fb.NY_MAX
#: Each matrix: its first word, its row width in the buffer, and which sizes bound its rows and columns.
MATRICES = {"K": (fb.B_K, N_MAX, ("2", "n")), "Lo": (fb.B_LO, NY_MAX, ("n", "ny")),
            "C": (fb.B_C, N_MAX, ("ny", "n")), "Ad": (fb.B_AD, N_MAX, ("n", "n")), "Bd": (fb.B_BD, 2, ("n", "2"))}


def _unused_words(buf) -> list:
    """The matrix and estimate words of ``buf`` outside its sizes' blocks."""
    sizes = {"n": int(buf[fb.B_N]), "ny": int(buf[fb.B_NY]), "2": 2}
    rows_max = {"K": 2, "Lo": N_MAX, "C": NY_MAX, "Ad": N_MAX, "Bd": N_MAX}
    unused = []
    for name, (first, width, (rows, cols)) in MATRICES.items():
        for i in range(rows_max[name]):
            for j in range(width):
                if i >= sizes[rows] or j >= sizes[cols]:
                    unused.append(first + i * width + j)
    unused += list(range(fb.B_X_HAT + sizes["n"], fb.B_X_HAT + N_MAX))
    return unused


def test_words_outside_the_kept_sizes_are_neither_read_nor_written():
    """A design of 4 kept states and 2 measurements (no yaw): NaN in every matrix word beyond
    its n x ny blocks and 1234.5 in the estimate beyond n change no output of 60 samples, bit
    for bit, and they are still there after them.  Catches a loop that runs one past its size
    (``<=`` for ``<`` over n or ny: it would read or write one of those words)."""
    clean = _buffer(yaw=False)
    assert (clean[fb.B_N], clean[fb.B_NY]) == (4.0, 2.0)
    poisoned = clean.copy()
    unused = _unused_words(clean)
    assert len(unused) == 2 * 2 + (6 * 3 - 4 * 2) + (3 * 6 - 2 * 4) + (36 - 16) + (12 - 8) + 2
    poisoned[unused] = math.nan
    spare = list(range(fb.B_X_HAT + 4, fb.B_X_HAT + N_MAX))
    poisoned[spare] = 1234.5                # finite: a write there (even of NaN) shows
    rng = np.random.default_rng(11)
    refusal = kernels.Refusal()
    for k in range(60):
        t = 0.02 * k
        x, y = np.zeros(fb.IO_SIZE), np.zeros(fb.IO_SIZE)
        x[:3] = y[:3] = rng.normal(0.0, 0.05, 3) + (0.3 * t, 0.35 * t, 0.0)
        assert fb.sample(clean, x, t, 1e6, refusal) == fb.OK
        assert fb.sample(poisoned, y, t, 1e6, refusal) == fb.OK
        assert x.tolist() == y.tolist(), k
    assert poisoned[spare].tolist() == [1234.5, 1234.5]
    assert np.isnan(poisoned[sorted(set(unused) - set(spare))]).all()
    used = [i for i in range(fb.BUF_SIZE) if i not in set(unused)]
    assert poisoned[used].tolist() == clean[used].tolist()


#: A smooth step that is neither 0 nor 1 at either end of its window (s(tau) = 0.25 (1 + tau + ... + tau^7)).
ODD_SMOOTH, ODD_SLOPE = [0.25] * 8, [0.5] * 7


@pytest.mark.parametrize("window", ["drive", "turning"])
def test_the_smooth_step_is_zero_at_its_start_and_one_at_its_end_whatever_it_is_between(window):
    """balance.c's smooth_step: s = 0 for t <= start, s = 1 for t >= end, the buffer's
    polynomial of tau = (t - start) / (end - start) strictly between.  With a polynomial that
    is 0.25 at tau = 0 and 2 at tau = 1, the desired x_d (= distance s) at t = start exactly is
    0, at t = end exactly the distance, just inside either end the polynomial (the boundaries
    ``<=`` and ``>=`` met exactly); the turning window drives the yaw reference, read through
    the command of a design whose only gain is on phi."""
    buf = _buffer(yaw=True)
    buf[fb.BUFFER["smooth"]], buf[fb.BUFFER["slope"]] = ODD_SMOOTH, ODD_SLOPE
    start, end = buf[fb.BUFFER[window]]
    distance, turn = buf[fb.B_DISTANCE], buf[fb.B_TURN]
    if window == "turning":                 # u = -K (x_hat - ref): only phi's reference counts, x_hat kept at 0
        buf[fb.BUFFER["K"]] = 0.0
        buf[fb.B_K + 2] = 1.0               # u_l = -(0 - ref_phi) = turn * a
        buf[fb.BUFFER["Lo"]] = 0.0
        buf[fb.BUFFER["Ad"]] = 0.0
        buf[fb.BUFFER["Bd"]] = 0.0
        buf[fb.B_V_MAX] = 1e9

    def reads(t):
        b, x = buf.copy(), np.zeros(fb.IO_SIZE)
        b[fb.B_STARTED] = 1.0               # started at rest at 0
        assert fb.sample(b, x, t, 1e6, kernels.Refusal()) == fb.OK
        out = dict(zip(fb.OUTPUTS, x[3:]))
        return out["x_d"] / distance if window == "drive" else out["v_l"] / turn

    def poly(tau):
        return sum(0.25 * tau ** i for i in range(8))

    assert reads(start) == 0.0 and reads(end) == 1.0
    inside_start, inside_end = math.nextafter(start, end), math.nextafter(end, start)
    assert reads(inside_start) == pytest.approx(0.25, rel=1e-12)
    assert reads(inside_end) == pytest.approx(2.0, rel=1e-12)
    assert reads(0.5 * (start + end)) == pytest.approx(poly(0.5), rel=1e-12)
    assert reads(start - 1.0) == 0.0 and reads(end + 1.0) == 1.0
