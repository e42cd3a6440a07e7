"""The derivator's buffer (thesis 7.2.3): its layout, read from the C kernel, and its packing.

The step is the C kernel ``pc_derivator_step`` (``kernels/src/derivator.c``), which
:class:`controller.derivators.Derivator` and its FMU slave call.
One float64 array holds the sizes, the step matrix, the rest state per unit angle and the
state with the newest input: the struct ``pc_derivator`` with its flexible array (layout in
``kernels/src/derivator.h``; the offsets here come from its exported field list).  The
compiled loop (:mod:`fmus.cosim.compiled`) calls ``pc_derivator_io`` on the same buffer.
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
#: Number of filter states n and of channels m; 1.0 once started (at rest at some angles).
V_STATES, V_CHANNELS, V_STARTED = (_FIELDS[name].start for name in ("states", "channels", "started"))
#: First entry of the step matrix, shape (2 + n, n + 1), row-major; then the rest state per
#: unit angle (n); then the state with the newest input, shape (n + 1, m).
V_MATRIX = _FIELDS["data"].start


def _offsets(n, m):
    rest = V_MATRIX + (2 + n) * (n + 1)
    state = rest + n
    return rest, state, state + (n + 1) * m


def run_state_words(buf: np.ndarray) -> range:
    """The indices of ``buf`` a run changes: ``V_STARTED`` and the state; every other word is
    configuration (the sizes the kernel's loops run over, the step matrix, the rest state),
    which a restored FMU state may not change (:mod:`fmus.slave.state`)."""
    n, m = int(buf[V_STATES]), int(buf[V_CHANNELS])
    _, state, end = _offsets(n, m)
    return (V_STARTED,) + tuple(range(state, end))


def pack(step_matrix: np.ndarray, rest_per_unit_angle: np.ndarray, channels: int) -> np.ndarray:
    """The buffer of ``pc_derivator_step`` for ``channels`` channels, not started."""
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
