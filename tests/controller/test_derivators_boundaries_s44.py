"""A Derivator always runs on the buffer it holds now (issue 31, training seed 4451 [13]).

The C kernel's call (its context over the buffer, scratch and I/O arrays) is cached per
Derivator and rebuilt when :attr:`Derivator.buf` is another array than the one it was built on:
a second :meth:`Derivator.reset` (which packs a new buffer, possibly for another number of
channels) or a buffer put back from elsewhere (a restored state). Either way the next step
reads and advances that buffer, never the one it held before.
"""
from __future__ import annotations

import numpy as np
import pytest

from controller.derivators import Derivator, bessel_lowpass_sos


def _parabola(k, a=0.3, b=-1.7):
    """A sample of q(t) = a t + b t^2 (t = k T, T = 1 ms): its estimates change every sample."""
    t = k * 1e-3
    return a * t + b * t * t


def test_a_second_reset_for_more_channels_runs_on_the_new_buffer_as_a_fresh_derivator_does():
    """After stepping a one-channel derivator, ``reset`` with two angles packs a new buffer: the
    estimates (two per step) and that buffer (the FMU state) are exactly a fresh derivator's."""
    used, fresh = Derivator(), Derivator()
    used.reset([0.2])
    for k in range(5):
        used.step([0.2 + _parabola(k)])
    old = used.buf
    used.reset([0.1, -0.4])
    fresh.reset([0.1, -0.4])
    assert used.buf is not old
    for k in range(1, 30):
        q = [0.1 + _parabola(k), -0.4 - 2 * _parabola(k)]
        got, want = used.step(q), fresh.step(q)
        for a, b in zip(got, want):
            assert a.shape == (2,)
            np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(used.buf, fresh.buf)


def test_a_buffer_put_back_from_a_copy_continues_from_that_copy_and_the_copy_is_advanced():
    """Save a copy of the buffer, run on, then make the copy the buffer (another array, as a
    restored state may be): the next steps repeat the estimates taken after the save exactly,
    and it is the copy now held that advances, not the array replaced."""
    d = Derivator()
    d.reset([0.5])
    for k in range(40):
        d.step([0.5 + _parabola(k)])
    saved = d.buf.copy()
    after_save = [np.concatenate(d.step([0.5 + _parabola(k)])) for k in range(40, 60)]
    replaced, d.buf = d.buf, saved.copy()
    replaced_before = replaced.copy()
    again = [np.concatenate(d.step([0.5 + _parabola(k)])) for k in range(40, 60)]
    np.testing.assert_array_equal(np.array(again), np.array(after_save))
    np.testing.assert_array_equal(replaced, replaced_before)   # the old array is no longer run on
    assert not np.array_equal(d.buf, saved)                    # the one held is


@pytest.mark.parametrize("order", [2, 8])
def test_a_cut_off_of_exactly_zero_is_refused_and_one_just_inside_either_end_is_designed(order):
    """The cut-off's range is open at both ends, 0 < fc < 1/(2T): fc = 0 is refused with the
    message naming the range (not left to scipy), and fc a little above 0 or one double
    below 1/(2T) gives sections of unit DC gain (each section's sum(b) = sum(a))."""
    T = 1e-3
    with pytest.raises(ValueError, match=rf"^cut-off 0.0 Hz must lie in \(0, {0.5 / T}\) Hz for T = {T} s$"):
        bessel_lowpass_sos(order, 0.0, T)
    for fc in (1e-2, np.nextafter(0.5 / T, 0.0)):
        sos = bessel_lowpass_sos(order, fc, T)
        assert sos.shape == (order // 2, 6)
        np.testing.assert_allclose(sos[:, :3].sum(axis=1), sos[:, 3:].sum(axis=1), rtol=1e-9, atol=0.0)
