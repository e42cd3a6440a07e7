"""What a compiled adapter is (:class:`Adapter`), the registry of adapters (:data:`ADAPTERS`,
:func:`register`) and the refusal of a system the compiled loop does not cover
(:class:`NotCompilable`).  The adapters of parcosim's models are in
:mod:`fmus.cosim.compiled_adapters`, the loop that runs them in :mod:`fmus.cosim.compiled`.
"""
from __future__ import annotations

import ctypes

import kernels


class NotCompilable(Exception):
    """The system (or one component's settings) has no compiled loop; the message says why."""


#: Model name -> its compiled adapter class (:func:`register`).
ADAPTERS: dict = {}


def register(cls):
    """Class decorator: ``cls`` is the compiled adapter of the model ``cls.model``."""
    ADAPTERS[cls.model] = cls
    return cls


class Adapter:
    """How one model's step runs in the compiled loop.

    A subclass sets ``model`` (the slave's model name), ``inputs`` and ``outputs`` (the
    variables of the layout of ``x``, the small array its kernel reads its inputs from and
    writes its outputs to: inputs first) and ``kernel``, the name of its model's C I/O step in
    the kernels' library (``pc_io_fn``, kernels/src/pc_common.h); :meth:`context` returns the
    ctypes struct of pointers to the model arrays that step advances (shared with the slave's
    model objects, so the compiled loop and the Python path step the same state).

    Parameters
    ----------
    name : str
        The instance.
    slave : fmus.slave.base.GuardedSlave
        The initialised in-process slave.
    h : float
        The step length this instance takes (the communication step / its sub-steps).

    Raises
    ------
    NotCompilable
        Settings the kernel does not cover (the Python path must run them).
    """

    model = ""
    inputs: tuple = ()
    outputs: tuple = ()
    kernel = ""

    def __init__(self, name: str, slave, h: float):
        self.name, self.slave, self.h = name, slave, h

    def context(self):
        """The ctypes object whose address the kernel gets as ``context`` (kept alive by
        the adapter)."""
        raise NotImplementedError

    def io_address(self) -> int:
        """The address of the I/O step: :attr:`kernel` in the kernels' library."""
        return ctypes.cast(getattr(kernels.library(), self.kernel), ctypes.c_void_p).value

    def refused(self, refusal, t: float) -> Exception | None:
        """The refusal of the step from ``t`` the kernel declined with ``refusal`` (its
        ``pc_refusal``), as the slave's own step raises it, made from the kernel's record and the
        buffers it left unchanged: nothing runs again.  None: the Python path takes that step
        (a sample off the controller's table with ``table_fallback``, a kernel whose refusals
        have no record builder here)."""
        return None

    def to_python(self) -> None:
        """Put state the kernel keeps outside the slave's objects back into them (before
        the Python path takes a step)."""

    def from_python(self) -> None:
        """Take state back from the slave's objects (after the Python path took a step)."""
