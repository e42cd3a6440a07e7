"""The words of the native loop's data arena that a run to the stop time never changes
(:func:`fmus.native.loopimage._run_to_stop`), on made-up blocks: a byte changed marks its whole
8-byte word, a block whose length is not whole words counts its last partial word as one (the
arena pads it so, ``_pad``), a word that changes and comes back is run state, and the words no
block covers stay fixed (seed 4001's survivor [222], the padding ``-b.size % WORD`` made
``b.size % WORD``: the same for whole words and half words, a crash for any other length)."""
from __future__ import annotations

import types

import numpy as np

from fmus.native.loopimage import WORD, Block, _run_to_stop


def _runs(blocks, changes, steps, words):
    """The fixed runs when step k applies ``changes[k]`` [(buffer, byte, value)]."""
    def run(values, record, k0, k1, t0, h):
        for buffer, byte, value in changes.get(k0, ()):
            buffer[byte] = value
        return types.SimpleNamespace(member=-1)

    plan = types.SimpleNamespace(run=run, adapters=[])
    stepper = types.SimpleNamespace(values=[0.0], record_slots=[0], start_time=0.0)
    arenas = types.SimpleNamespace(blocks=blocks)
    system = types.SimpleNamespace(steps=steps, step=1e-3)
    return _run_to_stop(system, plan, stepper, arenas, types.SimpleNamespace(values_word=words))


def test_a_changed_byte_marks_its_word_and_a_partial_last_word_counts_as_one():
    odd, whole = np.zeros(13, dtype=np.uint8), np.zeros(16, dtype=np.uint8)
    blocks = [Block(odd.ctypes.data, odd.size, None, 0), Block(whole.ctypes.data, whole.size, None, 2 * WORD)]
    # the partial word's last byte (12) changes; the whole block's second word changes and comes back
    runs = _runs(blocks, {0: [(odd, 12, 1)], 1: [(whole, 9, 7)], 2: [(whole, 9, 0)]}, steps=3, words=6)
    assert runs == [(0, 1), (2, 1), (4, 2)]      # words 1 and 3 are run state; 4 and 5 no block's


def test_blocks_of_every_length_mod_a_word_map_their_bytes_to_their_words():
    """Each length 1..17: the last byte changed marks exactly the word holding it."""
    for size in range(1, 18):
        data = np.zeros(size, dtype=np.uint8)
        words = -(-size // WORD) + 1
        runs = _runs([Block(data.ctypes.data, size, None, 0)], {0: [(data, size - 1, 1)]}, steps=1, words=words)
        last = (size - 1) // WORD
        expected = ([(0, last)] if last else []) + [(last + 1, words - last - 1)]
        assert runs == expected, size
