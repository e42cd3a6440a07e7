"""The wheeled pendulum's I/O step (kernels/src/wheeled.c) at the edges of its push window,
met exactly: the push is added over a step whose start t satisfies start - 1e-9 <= t <
start + duration - 1e-9 (1e-9 s absorbs the rounding of t = k h), checked against the plain
step with the torque added or not (session 44, training 4411 generalised)."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from plant import wheeled_kernel as K
from plant.wheeled import WheeledPendulum

START, DURATION, PUSH, H = 0.5, 0.25, 0.3, 1e-3


def _pushed(t: float) -> bool:
    """Whether the I/O step at t added the push: its state is the plain step's with tau_d + PUSH
    (and not the one without)."""
    settings = np.zeros(K.SETTINGS_SIZE)
    settings[K.S_SUBSTEPS], settings[K.S_COUNT], settings[K.S_LIMIT] = 2, 1e-3, 1e6
    settings[K.S_PUSH_TORQUE], settings[K.S_PUSH_START], settings[K.S_PUSH_DURATION] = PUSH, START, DURATION
    io_sim = WheeledPendulum(initial=dict(psi=0.05))
    x = np.zeros(3 + len(K.OUTPUT_NAMES))
    x[:3] = 0.01, -0.02, 0.001
    assert K.step_io(io_sim.prm, io_sim.y, settings, x, t, H, kernels.Refusal()) == K.OK
    outcomes = []
    for push in (0.0, PUSH):
        sim = WheeledPendulum(initial=dict(psi=0.05), substeps=2)
        sim.step(0.01, -0.02, H, 0.001 + push)
        outcomes.append(np.array_equal(io_sim.y, sim.y))
    assert outcomes.count(True) == 1, outcomes
    return outcomes[1]


def test_the_push_starts_exactly_a_nanosecond_before_its_start():
    """t = start - 1e-9 (the same double the kernel computes) is pushed, the double before it
    is not; start itself and start - 0.9 ns are, start - 1.1 ns is not (the constant 1e-9)."""
    first = START - 1e-9
    assert _pushed(first) and not _pushed(math.nextafter(first, 0.0))
    assert _pushed(START) and _pushed(START - 0.9e-9) and not _pushed(START - 1.1e-9)


def test_the_push_ends_exactly_a_nanosecond_before_its_end():
    """t = start + duration - 1e-9 is not pushed any more, the double before it is; the end
    itself is not, the end - 1.1 ns is (the window is [start, start + duration) less 1 ns)."""
    last = START + DURATION - 1e-9
    assert not _pushed(last) and _pushed(math.nextafter(last, 0.0))
    assert not _pushed(START + DURATION) and _pushed(START + DURATION - 1.1e-9)
    assert not _pushed(START + DURATION - 0.9e-9)
