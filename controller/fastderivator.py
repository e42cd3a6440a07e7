"""Compiled step of the derivator (thesis 7.2.3): one discrete state-space product per sample.

:class:`controller.derivators.Derivator` designs the chain (backward difference, Bessel
low-passes, their state space) in Python with scipy; every sample is the product

    [dq; ddq; next state] = [[C, D], [A, B]] @ [state; q]

for each channel, done here in one compiled call that the derivator, its FMU slave and the
compiled scene loop (:mod:`fmus.compiled`) share.  The products are summed in index order,
which may differ from numpy's BLAS in the last bit (docs/benchmarks.md gives the effect on
a scene).

One float64 array holds the sizes, the step matrix, the rest state per unit angle and the
state with the newest input, in the layout below (:func:`pack`).  A
kernel returns a status first; on a refusal it has changed nothing.

This module calls no compiled function of another file, so numba's on-disk cache
(``cache=True``, invalidated by this file's modification time only) cannot go stale.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

OK = 0
#: An input angle is not finite, or its magnitude is above the limit given.
BAD_INPUT = 1
#: An estimate came out non-finite.
NONFINITE_OUTPUT = 2

# --- layout ----------------------------------------------------------------------------------
#: Number of filter states n and of channels m; 1.0 once started (at rest at some angles).
V_STATES, V_CHANNELS, V_STARTED = 0, 1, 2
#: First entry of the step matrix, shape (2 + n, n + 1), row-major; then the rest state per
#: unit angle (n); then the state with the newest input, shape (n + 1, m).
V_MATRIX = 3


def _offsets(n, m):
    rest = V_MATRIX + (2 + n) * (n + 1)
    state = rest + n
    return rest, state, state + (n + 1) * m


def run_state_words(buf: np.ndarray) -> range:
    """The indices of ``buf`` a run changes: ``V_STARTED`` and the state; every other word is
    configuration (the sizes the kernel's loops run over, the step matrix, the rest state),
    which a restored FMU state may not change (:mod:`fmus.fmustate`)."""
    n, m = int(buf[V_STATES]), int(buf[V_CHANNELS])
    _, state, end = _offsets(n, m)
    return (V_STARTED,) + tuple(range(state, end))


def pack(step_matrix: np.ndarray, rest_per_unit_angle: np.ndarray, channels: int) -> np.ndarray:
    """The array of :func:`derivator_step` for ``channels`` channels, not started."""
    n = rest_per_unit_angle.size
    rest, state, size = _offsets(n, channels)
    buf = np.zeros(size)
    buf[V_STATES], buf[V_CHANNELS] = n, channels
    buf[V_MATRIX:rest] = np.ascontiguousarray(step_matrix, dtype=np.float64).ravel()
    buf[rest:state] = rest_per_unit_angle.ravel()
    return buf


def views(buf: np.ndarray):
    """The step matrix, shape (2 + n, n + 1), and the state with the newest input, shape
    (n + 1, m): views into ``buf``."""
    n, m = int(buf[V_STATES]), int(buf[V_CHANNELS])
    rest, state, end = _offsets(n, m)
    return buf[V_MATRIX:rest].reshape(2 + n, n + 1), buf[state:end].reshape(n + 1, m)


@njit(cache=True)
def reset(buf, q0):
    """At rest at the angles q0 (one per channel): both estimates zero."""
    n, m = int(buf[V_STATES]), int(buf[V_CHANNELS])
    rest = V_MATRIX + (2 + n) * (n + 1)
    state = rest + n
    for c in range(m):
        for j in range(n):
            buf[state + j * m + c] = buf[rest + j] * q0[c]
        buf[state + n * m + c] = q0[c]
    buf[V_STARTED] = 1.0


@njit(cache=True)
def derivator_step(buf, q, limit, out):
    """Take the angles q of a sample; out[0, c], out[1, c]: velocity and acceleration estimates.

    Not started yet: first at rest at q (the estimates are then zero).  Refused: a
    non-finite q or |q| > ``limit`` (:data:`BAD_INPUT`, nothing changed), non-finite
    estimates (:data:`NONFINITE_OUTPUT`, the filter state not advanced).
    """
    n, m = int(buf[V_STATES]), int(buf[V_CHANNELS])
    rest = V_MATRIX + (2 + n) * (n + 1)
    state = rest + n
    for c in range(m):
        if not (math.isfinite(q[c]) and abs(q[c]) <= limit):
            return BAD_INPUT
    if buf[V_STARTED] == 0.0:
        reset(buf, q)
    s = buf[state:state + (n + 1) * m].reshape((n + 1, m))
    s[n] = q
    # numpy's matmul and numba's np.dot call the same BLAS: bit-identical to the numpy product.
    outputs = np.dot(buf[V_MATRIX:rest].reshape((2 + n, n + 1)), s)
    finite = True
    for r in range(2):
        for c in range(m):
            out[r, c] = outputs[r, c]
            finite = finite and math.isfinite(outputs[r, c])
    if not finite:
        return NONFINITE_OUTPUT
    s[:n] = outputs[2:]
    return OK


@njit(cache=True)
def derivator_io(buf, x, limit):
    """Derivator (two channels): x = [q1, q2 | dq1, dq2, ddq1, ddq2]."""
    out = np.empty((2, 2))
    status = derivator_step(buf, x[0:2], limit, out)
    if status == OK:
        x[2], x[3], x[4], x[5] = out[0, 0], out[0, 1], out[1, 0], out[1, 1]
    return status
