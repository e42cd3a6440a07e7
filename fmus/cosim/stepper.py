"""A system's instances stepped one communication step at a time: the one Gauss-Seidel loop.

:class:`Stepper` is the loop of :func:`fmus.cosim.master.simulate`, cut at the step: built
from the instances and their stepping order, it initialises them, then each
:meth:`Stepper.step` advances every instance by one communication step and updates
the values of the signals that are read or recorded.  The master runs a whole system
with it; an FMU that contains a system (:mod:`fmus.systemfmu.cores`) steps it in its
``doStep``; the compiled mode (:mod:`fmus.cosim.compiled`) hands it the rest of a step a
kernel declined; the monolithic reference (:mod:`scenarios.reference`) steps its discrete
part with it.  The semantics (coupling, multi-rate groups, rows) are the master's: see
:mod:`fmus.cosim.master`.

The structure, built once:

* :attr:`Stepper.plan`: one :class:`Entry` per instance in stepping order (its inputs and
  outputs by name and slot, its sub-steps); :attr:`Stepper.groups`: consecutive entries of
  one sub-step count > 1 form a :class:`Group` (:func:`rate_groups`);
* the step's **program**: the groups unrolled into one flat sequence of :class:`Call`
  (one per instance and sub-step, with its time offset and step length, what it reads, how
  it sets its inputs, steps and stores its outputs).  :meth:`Stepper.step` runs that
  sequence and nothing else: the usual step, a step with some instances split into more
  sub-steps (a retried step, a program of its own) and the rest of a step from a given call
  (the compiled mode) are the same loop.  Jacobi coupling is the same program reading from
  snapshots (the values at the step's start, and a multi-rate group's values at each of its
  sub-steps' start) that the pull of a sub-step's first call takes.

The clock: step k starts at ``start_time + k h`` (:meth:`Stepper.at_step`; k the integer count
of steps taken), a call's sub-step j of n at that time plus ``j h / n``: every time is computed
from integers, none is a running sum (kernels/src/loop.c the same).

With ``kernels`` (the master's in-process mode), the groups of in-process slaves with a
compiled step become one call each run of them, a C call of their kernels
(:mod:`fmus.cosim.segments`); the program's other calls stay, and a split or partial step
runs the plain program after :meth:`Stepper.release`.
"""
from __future__ import annotations

import ctypes
import operator
from dataclasses import dataclass
from typing import Callable, NamedTuple

from fmus.cosim.backends import CoSimulationError
from fmus.cosim.slots import gatherer as _gatherer
from fmus.cosim.slots import gathering_pull
from fmus.cosim.slots import span as _span
from fmus.cosim.system import System, split_signal


@dataclass(frozen=True)
class Entry:
    """One instance in the stepping order: its connected inputs and the outputs it produces,
    by name and by slot (its outputs' slots are consecutive), and its sub-steps."""

    name: str
    instance: object
    inputs: tuple
    in_slots: tuple
    outputs: tuple
    out_slots: tuple
    substeps: int


@dataclass(frozen=True)
class Group:
    """Consecutive entries stepped ``substeps`` times per communication step together,
    exchanging their values at every sub-step (one entry when ``substeps`` is 1)."""

    substeps: int
    entries: tuple


class Call(NamedTuple):
    """One instance's step within a communication step, as :meth:`Stepper.step` runs it
    (a named tuple: unpacked in one go on the step's path).

    ``pull(reads)`` (None: no inputs) sets the inputs from the list ``reads`` (the values, or a
    Jacobi snapshot, which the pull of a sub-step's first call takes first);
    ``step(t + offset, dt)`` steps (False: refused, ``instance.step_refused(t)`` says why);
    ``values[out] = read(source)`` stores the outputs (``out`` a slice, or an index for one
    output read as a value)."""

    pull: Callable | None
    reads: list
    step: Callable
    offset: float
    dt: float
    read: Callable
    source: object
    out: object
    instance: object


class MemberCalls(NamedTuple):
    """How an instance's inputs are set, its step taken and its outputs read (:func:`member_calls`)."""

    pull: Callable | None
    step: Callable
    read: Callable
    source: object
    out: object
    instance: object


def member_calls(inst, in_slots, out_slots) -> MemberCalls:
    """What one step of ``inst`` takes from the stepper's values: ``pull(values)``
    sets the inputs from the values of ``in_slots`` (None: no inputs); ``step(t, h)`` steps (False: refused); ``values[out] = read(source)``
    stores the outputs.  An instance offers its own (``inst.step_calls``: the in-process
    slaves' attributes moved without a Python call: its class's, so that a wrapper delegating
    its attributes, whose ``do_step`` is another, is not bypassed); otherwise its
    ``set_inputs``, ``do_step`` and ``get_outputs``.  :mod:`benchmarks.bench_master` times these."""
    own = getattr(type(inst), "step_calls", None)
    if own is not None:
        return MemberCalls(*own(inst, in_slots, out_slots))
    pull = gathering_pull(inst.set_inputs, in_slots) if in_slots else None
    return MemberCalls(pull, inst.do_step, operator.call, inst.get_outputs, _span(out_slots), inst)


def rate_groups(plan) -> list:
    """Consecutive :class:`Entry` of equal sub-step count > 1 form one :class:`Group`."""
    groups = []
    for entry in plan:
        if entry.substeps > 1 and groups and groups[-1].substeps == entry.substeps:
            groups[-1] = Group(entry.substeps, groups[-1].entries + (entry,))
        else:
            groups.append(Group(entry.substeps, (entry,)))
    return groups


class _Program(NamedTuple):
    """A step's calls and where each (group, member, sub-step) starts in them."""

    calls: tuple
    index: dict


class Stepper:
    """Instances of ``system`` wired together, stepped in ``order``.

    Parameters
    ----------
    system : System
    instances : dict
        Instance name -> back-end instance (``fmus.cosim.backends.InProcessInstance`` or an FMU
        instance): ``variables``, ``bind``, ``enter_initialization``, ``exit_initialization``,
        ``set_inputs``, ``get_outputs``, ``do_step``; ``get_state``, ``set_state`` for :meth:`state`.
    order : sequence of str
        The stepping order (Gauss-Seidel) or the listing order (Jacobi).
    jacobi : bool
        Every instance reads the values all held at the step's start.
    kernels : class, optional
        Gauss-Seidel only: :class:`fmus.cosim.segments.Segments` (given by the master, which
        imports it: the stepper does not), the in-process slaves whose models have a compiled
        step take it (consecutive ones in one C call a step, their values in ``values``, a C
        array; :meth:`release` hands them back to Python).  None: every instance's own calls.

    Raises
    ------
    ValueError
        A recorded signal that is neither an output nor a connected input.
    """

    #: The kernel segments (:class:`fmus.cosim.segments.Segments`), False before the first step, None without.
    _kernels = None

    def __init__(self, system: System, instances: dict, order, jacobi: bool = False, kernels=None):
        self.system, self.instances, self.order, self.jacobi = system, instances, tuple(order), jacobi
        self.slots = {}
        feeds = {c.name: [] for c in system.components}
        for conn in system.connections:
            feeds[split_signal(conn.target)[0]].append(conn)
        sources = [c.source for c in system.connections]
        produced = {}
        for name in self.order:
            inst = instances[name]
            signals = [s for s in sources + list(system.record)
                       if split_signal(s)[0] == name and inst.variables[split_signal(s)[1]].causality == "output"]
            produced[name] = list(dict.fromkeys(signals))
            for signal in produced[name]:   # slots of the outputs first: each instance's are one slice
                self._slot(signal)
        plan = []
        for name in self.order:
            inst = instances[name]
            in_vars = [inst.variables[split_signal(c.target)[1]] for c in feeds[name]]
            out_vars = [inst.variables[split_signal(s)[1]] for s in produced[name]]
            inst.bind(in_vars, out_vars)
            plan.append(Entry(name, inst, tuple(v.name for v in in_vars), tuple(self._slot(c.source) for c in feeds[name]),
                              tuple(v.name for v in out_vars), tuple(self.slots[s] for s in produced[name]),
                              system.component(name).substeps))
        fed_by = {c.target: c.source for c in system.connections}   # a connected input records its source's slot
        recorded = [s if s in self.slots else fed_by.get(s) for s in system.record]
        unrecordable = [s for s, slot in zip(system.record, recorded) if slot is None]
        if unrecordable:
            raise ValueError(f"recorded signals must be outputs or connected inputs: {unrecordable}")
        #: The entries in stepping order (:class:`Entry`).
        self.plan = tuple(plan)
        #: The plan's multi-rate groups (:class:`Group`).
        self.groups = tuple(rate_groups(self.plan))
        self.record_slots = [self.slots[s] for s in recorded]
        self._record = _gatherer(self.record_slots)
        self._calls = {}     # instance name -> its MemberCalls, made once
        if kernels is not None and not jacobi:     # the segments' C call reads and writes the slots in place
            self.values = (ctypes.c_double * len(self.slots))()
            self._kernels, self._kernels_type = False, kernels     # built on the first step (the slaves set up)
        else:
            self.values = [0.0] * len(self.slots)
        self._program = self._program_of(self.groups)
        #: The clock: step ``k`` (steps taken since :meth:`initialize`) starts at ``time`` =
        #: ``start_time + k h``, computed from the integer k, never summed (module docstring).
        self.start_time, self.k, self.time = 0.0, 0, 0.0

    def _slot(self, signal):
        return self.slots.setdefault(signal, len(self.slots))

    def _member_calls(self, entry: Entry) -> MemberCalls:
        calls = self._calls.get(entry.name)
        if calls is None:
            calls = self._calls[entry.name] = member_calls(entry.instance, entry.in_slots, entry.out_slots)
        return calls

    def _program_of(self, groups) -> _Program:
        """The calls of one step of ``groups``, sub-steps unrolled (module docstring)."""
        h, values, jacobi = self.system.step, self.values, self.jacobi
        held = [] if jacobi else values      # Jacobi: the values at the step's start
        calls, index = [], {}
        for g, group in enumerate(groups):
            n = group.substeps
            dt = h / n
            reads = list(values) if jacobi and n > 1 else held   # Jacobi: a group's values at its sub-step's start
            own = [s for e in group.entries for s in e.out_slots]     # one slice: numbered in order
            produced = slice(min(own), max(own) + 1) if jacobi and n > 1 and own else None
            for j in range(n):
                for m, entry in enumerate(group.entries):
                    pull, step, read, source, out, inst = self._member_calls(entry)
                    if jacobi and m == 0:
                        pull = _snapshot(values, held, reads if n > 1 else None, produced, pull,
                                         first_of_step=g == 0 and j == 0, first_of_group=j == 0)
                    index[(g, m, j)] = len(calls)
                    calls.append(Call(pull, reads, step, j * dt, dt, read, source, out, inst))
        return _Program(tuple(calls), index)

    def initialize(self, start_time: float = 0.0) -> None:
        """Initialise every instance with its component's parameters and its connected inputs.

        All instances enter initialisation mode and get their parameters; then, in the
        order of :meth:`initialization_order`, each gets its connected inputs (from the
        outputs its sources hold: after their initialisation for sources that left it, their
        values in initialisation mode for the others), leaves initialisation mode, and its
        outputs are read.  So the t = 0 row is consistent: an output that depends on an input
        was computed from the connected value, not from the input's start value.
        """
        for c in self.system.components:
            self.instances[c.name].enter_initialization(c.parameters, start_time)
        self.at_step(0, start_time)
        for entry in self.plan:
            self._refresh(entry)
        values = self.values
        for entry in self.initialization_order():
            if entry.in_slots:
                entry.instance.set_inputs([values[i] for i in entry.in_slots])
            entry.instance.exit_initialization()
            self._refresh(entry)

    def at_step(self, k: int, start_time: float | None = None) -> None:
        """Set the clock to step ``k`` (from ``start_time``, or the one it has): ``time`` =
        ``start_time + k h``."""
        if start_time is not None:
            self.start_time = start_time
        self.k, self.time = k, self.start_time + k * self.system.step

    def initialization_order(self) -> list:
        """The plan's entries in the order instances leave initialisation mode: every
        source before its readers where the connections allow it; in a loop, the first
        instance in the stepping order (which keeps every sampled or feedthrough source
        before its readers) goes first."""
        sources = {name: set() for name in self.order}
        for conn in self.system.connections:
            src, dst = split_signal(conn.source)[0], split_signal(conn.target)[0]
            if src != dst:
                sources[dst].add(src)
        entries = {e.name: e for e in self.plan}
        placed, order = set(), []
        while len(order) < len(self.order):
            waiting = [name for name in self.order if name not in placed]
            name = next((n for n in waiting if sources[n] <= placed), waiting[0])
            placed.add(name)
            order.append(entries[name])
        return order

    def _refresh(self, entry: Entry) -> None:
        values = self.values
        for i, v in zip(entry.out_slots, entry.instance.get_outputs()):
            values[i] = v

    def refresh(self, inst) -> None:
        """Read ``inst``'s outputs into the values again (after its state was changed)."""
        self.release()
        self._refresh(next(e for e in self.plan if e.instance is inst))

    def state(self) -> dict:
        """A snapshot of the run: its clock (start time, step, time), the signals' values and
        each instance's state (``inst.get_state()``); :meth:`restore` goes back to it."""
        self.release()
        return {"start_time": self.start_time, "step": self.k, "time": self.time, "values": list(self.values),
                "instances": {name: inst.get_state() for name, inst in self.instances.items()}}

    def restore(self, state: dict) -> None:
        """Go back to ``state`` (of :meth:`state`; it can be restored again)."""
        if self._kernels:       # a slave's state may come with new buffers: the segments are made again
            self._kernels.release()
            self._kernels = False
        for name, inst in self.instances.items():
            inst.set_state(state["instances"][name])
        self.values[:] = state["values"]
        self.at_step(state["step"], state["start_time"])

    def free_state(self, state: dict) -> None:
        """Release the instances' states in ``state`` (FMU states live in the FMU)."""
        for name, inst in self.instances.items():
            inst.free_state(state["instances"][name])

    def row(self) -> tuple:
        """The recorded signals' present values, in ``system.record`` order."""
        return self._record(self.values)

    def recorder(self, data):
        """``record(k)``: :meth:`row` into ``data[k]`` (a float64 array, one column per recorded
        signal; with kernel segments, C-contiguous: written in one C call)."""
        if self._kernels is not None:
            return self._kernels_type.row_writer(self.values, self.record_slots, data)
        row = self.row

        def record(k):
            data[k] = row()
        return record

    def value(self, signal: str) -> float:
        """The present value of a connected or recorded ``signal``."""
        return self.values[self.slots[signal]]

    def step(self, split: dict | None = None, start: tuple | None = None) -> None:
        """One communication step of every instance from ``time`` (step k: ``start_time + k h``);
        then the clock stands at step k + 1 (:meth:`at_step`: computed, not ``time + h``).

        ``split`` (instance name -> n) takes this one step with those instances in n times
        their sub-steps (inputs held), as a master retrying a refused step does.  ``start``
        (group, member, sub-step) takes only the rest of the step from there on, as the
        compiled mode does when a kernel declined a step (Gauss-Seidel).  A refusal raises
        the instance's :class:`fmus.cosim.backends.CoSimulationError`."""
        kernels = self._kernels
        if kernels is not None:
            if split or start is not None:
                self.release()
            elif kernels and kernels.owned and kernels.whole is not None:   # the usual case: one C call
                t = self.time
                kernels.whole.step(t, self.system.step)
                self.at_step(self.k + 1)
                return
        calls = self._program.calls
        if kernels is not None and not split and start is None:
            calls = (kernels or self._segments()).acquire()
        if split:
            calls = self._program_of(rate_groups(
                [Entry(e.name, e.instance, e.inputs, e.in_slots, e.outputs, e.out_slots,
                       e.substeps * split.get(e.name, 1)) for e in self.plan])).calls
        if start is not None:
            calls = calls[self._program.index[start]:]
        t = self.time
        self._run(calls, t)
        # The next communication point from the step count, as libcosim's and fmpy 0.3's
        # masters time their steps: t + h would carry each step's rounding into the next.
        self.at_step(self.k + 1)

    def _run(self, calls, t: float) -> None:
        """Run ``calls`` (of a program) in the step from ``t``."""
        values = self.values
        try:
            for pull, reads, step, offset, dt, read, source, out, inst in calls:
                if pull is not None:
                    pull(reads)
                if step(t + offset, dt) is False:
                    raise inst.step_refused(t + offset)
                values[out] = read(source)
        except CoSimulationError:
            raise
        except Exception as exc:  # noqa: BLE001 - as the instance's do_step reports it
            raise CoSimulationError(inst.name, t + offset, str(exc)) from None

    def _segments(self):
        self._kernels = self._kernels_type(self)
        return self._kernels

    def release(self) -> None:
        """Hand the slaves stepped in C back to Python: their inputs' and outputs' attributes
        and their models' state as the Python path keeps them (:mod:`fmus.cosim.segments`)."""
        if self._kernels:
            self._kernels.release()


def _snapshot(values, held, group_reads, produced, pull, first_of_step, first_of_group):
    """The pull of Jacobi's first call in a group's sub-step: first the values at the step's
    start into ``held`` (first group), and for a multi-rate group its reads (``group_reads``):
    ``held`` at its first sub-step, then with its own outputs (the slice ``produced``, or None)
    as they are now; then the member's own ``pull`` (or None)."""
    if not first_of_step and group_reads is None:
        return pull

    def snapshot_and_pull(reads):
        if first_of_step:
            held[:] = values
        if group_reads is not None:
            if first_of_group:
                group_reads[:] = held
            elif produced is not None:
                group_reads[produced] = values[produced]
        if pull is not None:
            pull(reads)
    return snapshot_and_pull
