"""The compiled mode: a system's whole step loop run in C.

``simulate(system, mode="compiled")`` (``parcosim run SCENE --mode compiled``) builds the
in-process slaves and initialises them exactly as ``mode="inprocess"`` does (same
:class:`fmus.cosim.stepper.Stepper`, same stepping order, same t = 0 row).  Then each component's
**compiled adapter** (:data:`ADAPTERS`, one per model, in :mod:`fmus.cosim.compiled_adapters`) hands over
its model's C I/O step (``pc_<model>_io`` in kernels/src/) and a context pointing at the
buffers its model already steps with; :class:`Plan` lays the stepping order, the slots and
those pointers out as one ``pc_loop_plan``, and ``pc_loop_run`` (kernels/src/loop.c) steps
them with the connections as copies between fixed slots.  Same kernels, same buffers, same
order: the rows are bit-identical to the in-process run.  Nothing is generated or compiled
at run time: ``compile_s`` is building the plan.

Refusals: a kernel that cannot do exactly what the Python model would (a refused input,
a diverged step, a controller sample off its table) returns a non-zero status and its record
(``pc_refusal``) without changing anything; the loop stops there.  Where the adapter makes the
refusal from that record as the slave's own step would (:meth:`fmus.cosim.adapter.Adapter.refused`:
the position controller's samples, the FiveBarPlant's and ActuatedFiveBarPlant's steps), the
instance refuses the step with it and the run stops, nothing run again.  Otherwise the rest of that step runs in Python through the same slave objects
(:meth:`fmus.cosim.adapter.Adapter.to_python` first), which take the sample (e.g. the exact model
where the table has a hole) or raise the refusal; then the compiled loop goes on from the next
step.

A model without an adapter, a component given as an FMU file, Jacobi coupling, retried
steps or a stop time past the slaves' last time (:func:`check_compilable`) make the run fall back
to ``mode="inprocess"`` with a warning saying why (``Result.extra["fallback"]``), decided before
anything is loaded.  An adapter that declines its component's settings (:class:`fmus.cosim.adapter.NotCompilable`
from :class:`Plan`; they are known once the slave is set up) makes the same fallback from the
instances already initialised: nothing is loaded or initialised twice.
"""
from __future__ import annotations

import ctypes
import time as _time
from pathlib import Path

import numpy as np

import kernels
from kernels import Refusal

from fmus.slave.base import MAX_TIME
from fmus.cosim.backends import CoSimulationError
from fmus.cosim.adapter import ADAPTERS, NotCompilable
from fmus.cosim.context import Outcome


class _LoopPlan(ctypes.Structure):
    """``pc_loop_plan`` (kernels/src/loop.h)."""

    _int_p = ctypes.POINTER(ctypes.c_int)
    _fields_ = [("n_groups", ctypes.c_int), ("group_substeps", _int_p), ("group_end", _int_p),
                ("io", ctypes.POINTER(ctypes.c_void_p)), ("context", ctypes.POINTER(ctypes.c_void_p)),
                ("x", ctypes.POINTER(ctypes.c_void_p)),
                ("in_end", _int_p), ("in_x", _int_p), ("in_slot", _int_p),
                ("out_end", _int_p), ("out_x", _int_p), ("out_slot", _int_p),
                ("n_record", ctypes.c_int), ("record_slot", _int_p)]


class _LoopStop(ctypes.Structure):
    """``pc_loop_stop`` (kernels/src/loop.h)."""

    _fields_ = [("step", ctypes.c_int64), ("member", ctypes.c_int), ("substep", ctypes.c_int),
                ("time", ctypes.c_double), ("refusal", Refusal)]


def _ints(values) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.intc)


class Member:
    """One member of a :class:`LoopPlan`: its I/O step and context (addresses), its ``x``
    array, and its connections as (index in x, slot) pairs."""

    def __init__(self, io: int, context: int, x: np.ndarray, inputs=(), outputs=()):
        self.io, self.context, self.x = io, context, x
        self.inputs, self.outputs = list(inputs), list(outputs)


class LoopPlan:
    """A ``pc_loop_plan`` (kernels/src/loop.h) and the arrays it points into.

    Parameters
    ----------
    groups : list of (int, list of Member)
        The stepping order: groups of members stepped ``substeps`` times per step.
    record_slots : sequence of int
        The slots recorded after every step.
    """

    def __init__(self, groups, record_slots):
        group_substeps, group_end, members = [], [], []
        for substeps, group in groups:
            members += group
            group_substeps.append(substeps)
            group_end.append(len(members))
        self.members = members
        pairs = {"in": [m.inputs for m in members], "out": [m.outputs for m in members]}
        arrays = {"group_substeps": group_substeps, "group_end": group_end, "record_slot": list(record_slots)}
        for kind, lists in pairs.items():
            arrays[f"{kind}_end"] = np.cumsum([len(p) for p in lists]).tolist()
            arrays[f"{kind}_x"] = [x for p in lists for x, _ in p]
            arrays[f"{kind}_slot"] = [s for p in lists for _, s in p]
        self._arrays = {name: _ints(values) for name, values in arrays.items()}
        self._pointers = {"io": np.array([m.io for m in members], dtype=np.uintp),
                          "context": np.array([m.context for m in members], dtype=np.uintp),
                          "x": np.array([kernels.address(m.x) for m in members], dtype=np.uintp)}
        fields = {name: a.ctypes.data_as(ctypes.POINTER(ctypes.c_int)) for name, a in self._arrays.items()}
        fields.update({name: a.ctypes.data_as(ctypes.POINTER(ctypes.c_void_p)) for name, a in self._pointers.items()})
        self.struct = _LoopPlan(n_groups=len(group_substeps), n_record=len(arrays["record_slot"]), **fields)

    def run(self, values: np.ndarray, record: np.ndarray, k0: int, k1: int, t0: float, h: float) -> _LoopStop:
        """Steps k0 .. k1-1 in C, step k from t0 + k h (``values`` and the C-contiguous ``record``
        are written in place); the stop says where and why it ended."""
        stop = _LoopStop()
        _loop_run()(ctypes.byref(self.struct), kernels.address(values), kernels.address(record), k0, k1, t0, h,
                    ctypes.byref(stop))
        return stop


def adapter_of(entry, model: str, h: float):
    """The compiled adapter of ``entry`` (a :class:`fmus.cosim.stepper.Entry` of an in-process slave of
    ``model``) stepping ``h``, its ``x`` filled from the slave; :class:`NotCompilable` when there is none
    or it declines the slave's settings or connections."""
    name, slave = entry.name, entry.instance.slave
    cls = ADAPTERS.get(model)
    if cls is None:
        raise NotCompilable(f"component {name}: model {model!r} has no compiled adapter")
    try:
        slave.check_step_size(0.0, h)
    except ValueError as exc:
        raise NotCompilable(f"component {name}: {exc}") from None
    adapter = cls(name, slave, h)
    for kind, names, known in (("input", entry.inputs, cls.inputs), ("output", entry.outputs, cls.outputs)):
        unknown = [n for n in names if n not in known]
        if unknown:
            raise NotCompilable(f"component {name}: {kind}s {', '.join(unknown)} of {model} are not "
                                "in its compiled adapter")
    adapter.x = np.array([float(getattr(slave, n)) for n in cls.inputs + cls.outputs])
    return adapter


class Plan:
    """The compiled loop of one system: its adapters in stepping order and their
    :class:`LoopPlan`."""

    def __init__(self, system, stepper):
        _adapters()
        self.system, self.stepper = system, stepper
        self.adapters, self.positions = [], []   # positions: (group, member) of each adapter
        self._contexts = []
        h = system.step
        groups = []
        for g, group in enumerate(stepper.groups):
            members = []
            for m, entry in enumerate(group.entries):
                adapter = adapter_of(entry, system.component(entry.name).model, h / group.substeps)
                layout = adapter.inputs + adapter.outputs
                context = adapter.context()
                self._contexts.append(context)
                members.append(Member(adapter.io_address(), ctypes.addressof(context), adapter.x,
                                      [(layout.index(n), s) for n, s in zip(entry.inputs, entry.in_slots)],
                                      [(layout.index(n), s) for n, s in zip(entry.outputs, entry.out_slots)]))
                self.adapters.append(adapter)
                self.positions.append((g, m))
            groups.append((group.substeps, members))
        self.loop = LoopPlan(groups, stepper.record_slots)
        self.description = self._describe()

    def _describe(self) -> str:
        """The stepping order as text: one line per member (``# name (model): kernel``)."""
        lines = []
        for (g, _), a in zip(self.positions, self.adapters):
            substeps = self.stepper.groups[g].substeps
            lines.append(f"# {a.name} ({a.model}): {a.kernel}" + (f", {substeps} sub-steps" if substeps > 1 else ""))
        return "\n".join(lines)

    def run(self, values, record, k0, k1, t0, h) -> _LoopStop:
        """:meth:`LoopPlan.run` of the system's plan."""
        return self.loop.run(values, record, k0, k1, t0, h)


def _loop_run():
    return kernels.function("pc_loop_run", None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int64,
                            ctypes.c_int64, ctypes.c_double, ctypes.c_double, ctypes.c_void_p)


def check_compilable(system, coupling: str, retry_substeps) -> None:
    """Raise :class:`NotCompilable` for what the compiled loop does not cover, before anything is built."""
    from fmus.cosim.foreign import is_fmu_file

    if coupling != "gauss-seidel":
        raise NotCompilable(f"coupling {coupling!r}: the compiled loop is Gauss-Seidel only")
    if retry_substeps is not None:
        raise NotCompilable("retry_substeps: retried steps need FMU states, which the compiled loop does not take")
    for c in system.components:
        if is_fmu_file(c.model):
            raise NotCompilable(f"component {c.name} is an FMU file ({Path(c.model).name}), which has no compiled "
                                "adapter")
        if c.model not in _adapters():
            raise NotCompilable(f"component {c.name}: model {c.model!r} has no compiled adapter")
    if not system.stop_time + system.step <= MAX_TIME:
        raise NotCompilable(f"stop time {system.stop_time!r} s is beyond {MAX_TIME:g} s")


def _adapters() -> dict:
    from fmus.cosim import compiled_adapters  # noqa: F401 - registers the adapters of parcosim's models

    return ADAPTERS


def _refuse_declined(adapter, instance, stop, dt) -> None:
    """Raise the refusal of the (sub-)step ``adapter``'s kernel declined at ``stop``, made from the
    kernel's record (:meth:`fmus.cosim.adapter.Adapter.refused`), as the instance's own step
    would; return when the Python path is to take that step."""
    t = stop.time + stop.substep * dt
    refused = adapter.refused(stop.refusal, t)
    if refused is not None:
        adapter.slave.refuse_step(refused, t)
        raise instance.step_refused(t)


def run_compiled(run, stepper, plan: Plan) -> Outcome:
    """Step ``run.system`` (a :class:`fmus.cosim.context.RunContext`) from its initialised
    ``stepper`` in the compiled loop ``plan``; the rest of a step a kernel declines runs in
    Python (:meth:`fmus.cosim.stepper.Stepper.step` from that member on)."""
    system = run.system
    h, steps = system.step, system.steps
    data = np.full((steps + 1, len(system.record)), np.nan)
    data[0] = stepper.row()
    values = np.array(stepper.values, dtype=float)
    start, cpu_start = _time.perf_counter(), _time.thread_time()
    error, interrupted, done = None, False, 0
    chunk = max(1, steps // 100)
    python_steps = 0
    try:
        while done < steps:
            if run.interrupt.requested:
                raise KeyboardInterrupt
            end = min(steps, done + chunk)
            stop = plan.run(values, data, done, end, stepper.start_time, h)
            done = stop.step
            if stop.member >= 0:     # a kernel declined step k: the Python path takes the rest of it
                for a in plan.adapters:
                    a.to_python()
                    a.slave._next_time = None   # the slaves did not see the compiled steps
                g, m = plan.positions[stop.member]
                group = stepper.groups[g]
                _refuse_declined(plan.adapters[stop.member], group.entries[m].instance, stop, h / group.substeps)
                stepper.values[:] = values.tolist()
                stepper.at_step(done)
                stepper.step(start=(g, m, stop.substep))
                for a in plan.adapters:
                    a.from_python()
                values[:] = stepper.values
                done += 1
                data[done] = stepper.row()
                python_steps += 1
            if run.progress is not None:
                run.progress(done / steps)
    except CoSimulationError as exc:
        error = exc
    except KeyboardInterrupt:
        interrupted = True
    wall = _time.perf_counter() - start
    extra = {"python_steps": python_steps, "plan": plan.description, "cpu_s": _time.thread_time() - cpu_start}
    return Outcome(data[:done + 1], error, interrupted, wall, extra=extra)
