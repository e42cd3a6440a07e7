"""The position law's C kernel inside the numba-compiled scene loop (:mod:`fmus.compiled`).

Temporary: until the compiled loop calls the kernels' ``pc_io_fn`` functions from C, its
generated numba source calls :func:`law_io`, which calls ``pc_law_io`` (and, for the exact
model, :func:`plant.fast5r.inverse_terms` and ``pc_law_resume``) by symbol: llvmlite resolves
the names to the loaded library, so numba's cache of the loop stays valid across processes.
"""
from __future__ import annotations

import ctypes

import llvmlite.binding as llvm
from numba import njit, types

import kernels
from plant.fast5r import inverse_terms

from . import law

for _name in ("pc_law_io", "pc_law_resume"):
    llvm.add_symbol(_name, ctypes.cast(getattr(kernels.library(), _name), ctypes.c_void_p).value)
_io = types.ExternalFunction("pc_law_io", types.int32(types.uintp, types.uintp, types.float64, types.float64,
                                                      types.uintp))
_resume = types.ExternalFunction("pc_law_resume", types.int32(types.uintp, types.float64, types.uintp))

NEEDS_TERMS = law.NEEDS_TERMS
Q0, DQ0, OUT0 = law.Q.start, law.DQ.start, law.OUT.start


@njit(cache=True, error_model="numpy")
def law_io(context, refusal, x, t, h):
    """``pc_law_io`` on the I/O array x (12 inputs, 6 outputs); ``context`` holds the address
    of the controller's ``pc_law_context``, ``refusal`` 2 words for its ``pc_refusal``.  0 or
    the kernel's code (the controller's state unchanged)."""
    return _io(context[0], x.ctypes.data, t, h, refusal.ctypes.data)


@njit(cache=True, error_model="numpy")
def law_exact_io(context, refusal, x, t, h, scratch, p, terms):
    """:func:`law_io` of the exact model: its terms from :func:`plant.fast5r.inverse_terms`
    (``p``) at the pose the kernel left in ``scratch``."""
    st = _io(context[0], x.ctypes.data, t, h, refusal.ctypes.data)
    if st != NEEDS_TERMS:
        return st
    inverse_terms(p, scratch[Q0:Q0 + 7], scratch[DQ0:DQ0 + 7], terms)
    st = _resume(context[0], h, refusal.ctypes.data)
    if st == 0:
        for k in range(6):
            x[12 + k] = scratch[OUT0 + k]
    return st
