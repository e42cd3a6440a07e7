"""In-process steps of C-backed slaves taken in C: the stepper's kernel segments.

An in-process slave of parcosim whose model has a compiled adapter
(:mod:`fmus.cosim.compiled_adapters`) and whose settings it accepts steps with one C call,
its model's I/O step (``pc_<model>_io``) on the very buffers the slave's Python step advances.
:class:`Segments` lays the stepper's consecutive groups of such members out as segments:
each is one ``pc_loop_run`` over one communication step (kernels/src/loop.c), which copies
the connected values from the stepper's slots into each member's ``x``, steps it, and copies
its outputs back.  So a step of the bench scene is one ctypes call instead of eight slaves'
Python ``do_step`` with attribute sets and gets around a ctypes call each.  Any other
instance (a user's Python slave, an FMU, a model whose settings its adapter declines) keeps
its Python calls between the segments.

While the segments step them (``owned``), the C-backed slaves' inputs and outputs are in
their ``x`` (and the stepper's slots), not in their attributes, and the slave's Python
clock check is not fed.  :meth:`Segments.release` hands them back to Python (attributes set
from ``x``, state the kernel keeps apart put back: :meth:`fmus.cosim.adapter.Adapter.to_python`);
:meth:`Segments.acquire` takes them again.  The stepper releases before anything that reads
or steps a slave in Python (a state, a refresh, a split or partial step, the end of a run).

A kernel that cannot do exactly what the Python model would (a refused input, a diverged
step, a controller sample off its table) declines without changing anything: that
segment's members are released, the rest of the segment's step runs in Python through the
stepper's own calls (which raise the slave's refusal with its record, or take the sample),
and they are taken again.  The rows are those of the Python path: same kernels, same
buffers, same order (the compiled mode, :mod:`fmus.cosim.compiled`, runs the same plans).
"""
from __future__ import annotations

import ctypes

import numpy as np

import kernels
from fmus.cosim.adapter import NotCompilable
from fmus.cosim.compiled import LoopPlan, Member, _LoopStop, _adapters, adapter_of
from fmus.cosim.stepper import Call
from fmus.slave.registry import SLAVES


def kernel_adapters(stepper) -> list:
    """Per group of ``stepper.groups``, its members' adapters, or None when one of its members
    has no compiled step in process (not an in-process parcosim slave of its model ready to
    step, no adapter, settings its adapter declines)."""
    adapters = _adapters()
    h = stepper.system.step
    found = []
    for group in stepper.groups:
        members = []
        for entry in group.entries:
            model = stepper.system.component(entry.name).model
            slave = getattr(entry.instance, "slave", None)
            cls = adapters.get(model)
            # parcosim's own class of the model only; a slave not initialised (or refused) says so
            # from its Python step
            if slave is None or cls is None or _qualified(type(slave)) != f"fmus.slaves.{SLAVES.get(model)}.{model}" \
                    or not getattr(slave, "_ready", False):
                break
            try:
                members.append(adapter_of(entry, model, h / group.substeps))
            except NotCompilable:
                break
        found.append(members if len(members) == len(group.entries) else None)
    return found


def _qualified(cls) -> str:
    return f"{cls.__module__}.{cls.__qualname__}"


class Segment:
    """Consecutive groups of C-backed members (``groups``, indices into ``stepper.groups``;
    ``adapters``, per group its members') stepped by one ``pc_loop_run`` per step."""

    def __init__(self, stepper, groups: list, adapters: list):
        self.stepper, self.adapters = stepper, [a for members in adapters for a in members]
        self._contexts, self.positions, loop_groups = [], [], []
        for g, members in zip(groups, adapters):
            group = stepper.groups[g]
            loop = []
            for m, (entry, a) in enumerate(zip(group.entries, members)):
                layout = a.inputs + a.outputs
                self._contexts.append(a.context())
                loop.append(Member(a.io_address(), ctypes.addressof(self._contexts[-1]), a.x,
                                   [(layout.index(n), s) for n, s in zip(entry.inputs, entry.in_slots)],
                                   [(layout.index(n), s) for n, s in zip(entry.outputs, entry.out_slots)]))
                self.positions.append((g, m))
            loop_groups.append((group.substeps, loop))
        last = stepper.groups[groups[-1]]
        #: Where the segment's calls end in the stepper's program (a declined step goes on there).
        self.end = stepper._program.index[(groups[-1], len(last.entries) - 1, last.substeps - 1)] + 1
        self.loop = LoopPlan(loop_groups, ())
        self._call = _LoopCall(plan=ctypes.addressof(self.loop.struct), values=ctypes.addressof(stepper.values),
                               h=stepper.system.step)
        self._run = _call_step()
        self._ref = ctypes.byref(self._call)

    def step(self, t: float, h: float) -> bool:
        """The members' step from ``t`` (of length ``h``, the stepper's); from a member whose
        kernel declined, the rest of the segment through the stepper's Python calls.  True (a
        refusal raises)."""
        call = self._call
        call.t = t      # the stepper's clock (k stays 0: pc_loop_run starts the step at t)
        if self._run(self._ref) >= 0:
            stop = call.stop
            g, m = self.positions[stop.member]
            program = self.stepper._program
            self.release()
            try:
                self.stepper._run(program.calls[program.index[(g, m, stop.substep)]:self.end], t)
            finally:
                self.acquire()
        return True

    def release(self) -> None:
        """The members' inputs, outputs and kernel-kept state back in the slaves."""
        for a in self.adapters:
            a.to_python()
            slave = a.slave
            for name, value in zip(a.inputs + a.outputs, a.x.tolist()):
                setattr(slave, name, value)
            slave._next_time = None       # the slave did not see the steps taken in C

    def acquire(self) -> None:
        """The members' inputs, outputs and state from the slaves into the kernels' buffers."""
        for a in self.adapters:
            a.from_python()
            a.x[:] = [float(getattr(a.slave, n)) for n in a.inputs + a.outputs]


def _no_outputs(source):
    return ()


class Segments:
    """The stepper's program with its C-backed groups as :class:`Segment` calls (``calls``),
    and whether the segments hold their slaves (``owned``)."""

    def __init__(self, stepper):
        self.stepper, self.owned, self.segments = stepper, False, []
        program, h = stepper._program, stepper.system.step
        found = kernel_adapters(stepper)
        calls, g = [], 0
        while g < len(found):
            if found[g] is None:
                group = stepper.groups[g]
                first = program.index[(g, 0, 0)]
                calls += program.calls[first:first + group.substeps * len(group.entries)]
                g += 1
                continue
            end = g
            while end < len(found) and found[end] is not None:
                end += 1
            segment = Segment(stepper, list(range(g, end)), found[g:end])
            self.segments.append(segment)
            calls.append(Call(None, None, segment.step, 0.0, h, _no_outputs, None, slice(0, 0),
                              stepper.groups[g].entries[0].instance))
            g = end
        self.calls = tuple(calls)
        #: The one segment when it is the whole step (its call alone, in place of the program's loop).
        self.whole = self.segments[0] if len(self.calls) == 1 and self.segments else None

    def acquire(self) -> tuple:
        """Take the slaves (their values into the kernels' buffers); the program's calls."""
        if not self.owned:
            for segment in self.segments:
                segment.acquire()
            self.owned = True
        return self.calls

    def release(self) -> None:
        """Hand the slaves back to Python (their attributes current)."""
        if self.owned:
            for segment in self.segments:
                segment.release()
            self.owned = False

    @staticmethod
    def row_writer(values, slots, data):
        """``record(k)``: the values of ``slots`` in ``values`` (a C array of doubles) into row ``k``
        of ``data`` (C-contiguous float64, one column per slot) in one C call: ``pc_loop_run``
        of a plan with no members, which records row k after "step" k - 1."""
        if data.dtype != np.float64 or not data.flags.c_contiguous or data.ndim != 2 or data.shape[1] != len(slots):
            raise ValueError(f"a row writer needs a C-contiguous float64 array of {len(slots)} columns")
        plan, run, rows = LoopPlan([], slots), _call_step(), data.shape[0]
        call = _LoopCall(plan=ctypes.addressof(plan.struct), values=ctypes.addressof(values), record=data.ctypes.data)
        ref = ctypes.byref(call)

        def record(k: int) -> None:
            if not 0 < k < rows:
                raise IndexError(f"row {k} of {rows}")
            call.k = k - 1
            run(ref)
        record.keep = (plan, data)     # what the addresses point into, alive as long as record
        return record


class _LoopCall(ctypes.Structure):
    """``pc_loop_call`` (kernels/src/loop_call.h)."""

    _fields_ = [("plan", ctypes.c_void_p), ("values", ctypes.c_void_p), ("record", ctypes.c_void_p),
                ("k", ctypes.c_int), ("t", ctypes.c_double), ("h", ctypes.c_double), ("stop", _LoopStop)]


def _call_step():
    """``pc_loop_call_step``, called with the GIL held (``ctypes.PyDLL``: the kernels call no
    Python and take microseconds) and no argument conversion (a ``byref`` made once)."""
    function = ctypes.PyDLL(kernels.library()._name).pc_loop_call_step
    function.restype = ctypes.c_int
    return function
