"""The derivator's C step (kernels/src/derivator.c) at the ends of the sizes it accepts, with
sections that pass their input through (b0 = 1, every other coefficient 0): the estimates are
then exactly the backward differences rate (q - q_prev) and rate (dq - dq_prev), whatever the
sizes, so each boundary of the layout check (states in [2, 64] and even, channels in [1, 64],
velocity sections in [0, n/2 - 1], a scratch of at least n m words) is met on both sides with a
known answer; and the scratch, used only over two channels (derivator.h), is the next state
there and untouched otherwise (session 44, training 4411)."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from controller import derivators, fastderivator

T = 1e-3
#: A second-order section that passes its input through: rows [b0 b1 b2 1 a1 a2].
THROUGH = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0]


def _buffer(velocity: int, acceleration: int, channels: int) -> np.ndarray:
    sections = np.array([THROUGH] * (velocity + acceleration)).reshape(-1, 6)
    return fastderivator.pack(T, sections[:velocity], sections[velocity:], channels)


def _step(buf, q, scratch=None, limit=math.inf):
    n, m = int(buf[fastderivator.V_STATES]), int(buf[fastderivator.V_CHANNELS])
    scratch = np.zeros(n * m) if scratch is None else scratch
    out, refusal = np.zeros(2 * q.size), kernels.Refusal()
    context = derivators._Context(kernels.address(buf), kernels.address(scratch), buf.size, scratch.size, limit)
    code = derivators._STEP(context, kernels.address(q), limit, kernels.address(out), refusal)
    return code, out, refusal


@pytest.mark.parametrize("velocity, acceleration, channels", [
    (0, 0, 1), (0, 0, 2), (0, 0, 3), (31, 0, 64), (0, 31, 1), (15, 16, 3), (1, 1, 64), (2, 0, 5)])
def test_pass_through_sections_leave_the_backward_differences_at_every_accepted_size(velocity, acceleration,
                                                                                     channels):
    """From rest at the first angles, sample k's estimates are rate (q_k - q_k-1) and rate
    (dq_k - dq_k-1) on every channel, computed here: for the fewest states (2: no section), the
    most (64: 31 sections, all of F_v's or all of F_a's), one channel, the most (64), an odd
    count (the last paired with itself), pairs side by side.  Catches a size refused at its
    bound (``<`` for ``<=``), a channel's numbers written into another's, a lane dropped."""
    buf = _buffer(velocity, acceleration, channels)
    rng = np.random.default_rng(channels + 7 * velocity)
    q_prev = dq_prev = None
    for k in range(4):
        q = rng.normal(0.0, 1.0, channels)
        code, out, _ = _step(buf, q)
        assert code == fastderivator.OK, k
        dq = np.zeros(channels) if q_prev is None else (1.0 / T) * (q - q_prev)
        ddq = np.zeros(channels) if dq_prev is None else (1.0 / T) * (dq - dq_prev)
        assert out[:channels].tolist() == dq.tolist(), k
        assert out[channels:].tolist() == ddq.tolist(), k
        q_prev, dq_prev = q, dq


@pytest.mark.parametrize("word, value, index", [
    ("V_STATES", 66.0, 0), ("V_STATES", 0.0, 0), ("V_CHANNELS", 65.0, 1), ("V_CHANNELS", 0.0, 1),
    ("V_VELOCITY_SECTIONS", None, 4)])
def test_one_past_each_size_bound_is_refused_naming_its_word(word, value, index):
    """One beyond each bound the previous test meets: 66 states (or 0), 65 channels (or 0), a
    velocity sections' count of n/2 (one more than the sections): BAD_LAYOUT naming that word
    (derivator.h's index) and its value, the buffer unchanged (the buffer's length made to fit
    the sizes where it can, so that the size word itself is what is refused)."""
    if word == "V_STATES" and value == 66.0:
        buf = _buffer(32, 0, 1)                    # 32 sections: 66 states, the length fits them
    elif word == "V_CHANNELS" and value == 65.0:
        buf = _buffer(1, 1, 65)                    # its length fits 65 channels
    else:
        buf = _buffer(2, 1, 2)
        if value is None:
            value = buf[fastderivator.V_STATES] / 2    # 8 states: velocity sections 4 of 3 sections
        buf[getattr(fastderivator, word)] = value
    assert buf[getattr(fastderivator, word)] == value
    saved = buf.copy()
    m = int(buf[fastderivator.V_CHANNELS]) if buf[fastderivator.V_CHANNELS] >= 1 else 1
    code, _, refusal = _step(buf, np.zeros(m), scratch=np.zeros(66 * 65))
    assert (code, refusal.index, refusal.value) == (fastderivator.BAD_LAYOUT, index, value)
    np.testing.assert_array_equal(buf, saved)


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
def test_a_scratch_of_exactly_n_m_words_is_taken_and_one_word_less_refused(channels):
    """sizes(): a scratch of n m words (what pc_derivator_scratch_words asks for) is enough;
    n m - 1 is refused as BAD_LAYOUT naming the scratch's length (index 3) with that length."""
    buf = _buffer(1, 1, channels)
    n = int(buf[fastderivator.V_STATES])
    q = np.linspace(0.1, 0.4, channels)
    assert _step(buf.copy(), q, scratch=np.zeros(n * channels))[0] == fastderivator.OK
    code, _, refusal = _step(buf, q, scratch=np.zeros(n * channels - 1))
    assert (code, refusal.index, refusal.value) == (fastderivator.BAD_LAYOUT, 3, float(n * channels - 1))


@pytest.mark.parametrize("channels", [1, 2, 3, 5])
def test_the_scratch_is_the_next_state_over_two_channels_and_untouched_up_to_two(channels):
    """derivator.h: the scratch holds "the next state before it replaces the state (over two
    channels)"; one pair is updated in place (derivator.c: "one pair: next waits in place").
    After a step the scratch of more than two channels equals the new state rows, that of one
    or two channels still holds what the caller put there (training 4411 [10]: ``m >= 2``
    wrote it for a single pair)."""
    buf = _buffer(2, 1, channels)
    n = int(buf[fastderivator.V_STATES])
    scratch = np.full(n * channels, -7.25)
    q = np.linspace(0.3, -0.2, channels)
    assert _step(buf, q, scratch=scratch)[0] == fastderivator.OK
    assert _step(buf, q + 0.01, scratch=scratch)[0] == fastderivator.OK
    _, state = fastderivator.views(buf)
    if channels > 2:
        assert scratch.tolist() == state[:n].ravel().tolist()
    else:
        assert (scratch == -7.25).all()
