"""The derivator's buffer (thesis 7.2.3): its layout, read from the C kernel, and its packing.

The step is the C kernel ``pc_derivator_step`` (``kernels/src/derivator.c``), which
:class:`controller.derivators.Derivator` and its FMU slave call.
One float64 array holds the sizes, the design (1/T and the second-order sections of the two
low-passes) and the state with the newest input: the struct ``pc_derivator`` with its flexible
array (layout in ``kernels/src/derivator.h``; the offsets here come from its exported field
list).  The compiled loop (:mod:`fmus.cosim.compiled`) calls ``pc_derivator_io`` on the same
buffer.
"""
from __future__ import annotations

import numpy as np

import kernels

OK = 0
#: An input angle is not finite, or its magnitude is above the limit given.
BAD_INPUT = 1
#: An estimate came out non-finite.
NONFINITE_OUTPUT = 2
#: The sizes in the buffer do not fit its length (a forged or damaged buffer).
BAD_LAYOUT = 3

_FIELDS = kernels.layout("pc_derivator_fields")
#: Number of state words n of a channel and of channels m; 1.0 once started (at rest at some
#: angles); the velocity low-pass's sections S_v.
V_STATES, V_CHANNELS, V_STARTED, V_VELOCITY_SECTIONS = (
    _FIELDS[name].start for name in ("states", "channels", "started", "velocity_sections"))
#: 1/T; then the sections, shape (S, 5), rows b0 b1 b2 a1 a2 (S = n/2 - 1); then the state with
#: the newest input, shape (n + 1, m).
V_RATE = _FIELDS["data"].start
V_SECTIONS = V_RATE + 1
#: Coefficients of a section in the buffer: b0 b1 b2 a1 a2.
SECTION_WORDS = 5


def _offsets(n, m):
    state = V_SECTIONS + (n // 2 - 1) * SECTION_WORDS
    return state, state + (n + 1) * m


def run_state_words(buf: np.ndarray) -> range:
    """The indices of ``buf`` a run changes: ``V_STARTED`` and the state; every other word is
    configuration (the sizes the kernel's loops run over, 1/T, the sections), which a restored
    FMU state may not change (:mod:`fmus.slave.state`)."""
    n, m = int(buf[V_STATES]), int(buf[V_CHANNELS])
    state, end = _offsets(n, m)
    return (V_STARTED,) + tuple(range(state, end))


def pack(T: float, velocity_sos: np.ndarray, acceleration_sos: np.ndarray, channels: int) -> np.ndarray:
    """The buffer of ``pc_derivator_step`` for ``channels`` channels, not started: the backward
    differences at sample time ``T`` and the two low-passes' second-order sections (rows [b0 b1
    b2 1 a1 a2], a0 = 1)."""
    sos = np.vstack([velocity_sos, acceleration_sos]).astype(np.float64)
    if sos.ndim != 2 or sos.shape[1] != 6 or not np.all(sos[:, 3] == 1.0):
        raise ValueError(f"sections {sos.tolist()!r} must be rows [b0 b1 b2 1 a1 a2] (a0 = 1)")
    n = 2 + 2 * len(sos)
    state, size = _offsets(n, channels)
    buf = np.zeros(size)
    buf[V_STATES], buf[V_CHANNELS], buf[V_VELOCITY_SECTIONS] = n, channels, len(velocity_sos)
    buf[V_RATE] = 1.0 / T
    buf[V_SECTIONS:state] = sos[:, [0, 1, 2, 4, 5]].ravel()
    return buf


def views(buf: np.ndarray):
    """The sections, shape (S, 5) (b0 b1 b2 a1 a2), and the state with the newest input, shape
    (n + 1, m): views into ``buf``."""
    n, m = int(buf[V_STATES]), int(buf[V_CHANNELS])
    state, end = _offsets(n, m)
    return buf[V_SECTIONS:state].reshape(-1, SECTION_WORDS), buf[state:end].reshape(n + 1, m)
