"""The compiled mode: a system's whole step loop generated for its wiring and compiled.

``simulate(system, mode="compiled")`` (``parcosim run SCENE --mode compiled``) builds the
in-process slaves and initialises them exactly as ``mode="inprocess"`` does (same
:class:`fmus.stepper.Stepper`, same stepping order, same t = 0 row).  Then each component's
**compiled adapter** (:data:`ADAPTERS`, one per model, in :mod:`fmus.adapters`) hands over
the float64 arrays its model already steps with (the kernels of ``plant/fast5r.py``,
``motor/fastdrive.py``, ``controller/fastlaw.py``, ...) and the line of source that calls its
kernel; :func:`generate` writes one Python function that runs the steps in the stepping order
with the connections as copies between fixed slots, compiled by numba.  Same kernels, same
arrays, same order: the rows are bit-identical to the in-process run.

Caching: the generated source goes to ``<cache>/loop_<sha>.py`` where the sha covers the
source and the text of every kernel module it calls (numba's own cache only watches the
file of the function it compiled, so a changed kernel gives a new file instead of a stale
one).  Parameters live in the arrays, not in the source: scenes with the same wiring (all
16 bench scenes) share one compiled loop.  ``compile_s`` is importing it and compiling it or
loading numba's cache; the stepping's wall time starts after that.

Refusals: a kernel that cannot do exactly what the Python model would (a refused input,
a diverged step, a controller sample off its table) returns a non-zero status without
changing anything; the loop stops there, and the rest of that step runs in Python through
the same slave objects (:meth:`Adapter.to_python` first), which raise the refusal's
message or take the sample (e.g. the exact model where the table has a hole); then the
compiled loop goes on from the next step.

A model without an adapter, a component given as an FMU file, Jacobi coupling, retried
steps or an adapter that declines its settings (:class:`NotCompilable`) make the run fall
back to ``mode="inprocess"`` with a warning saying why (``Result.extra["fallback"]``).
"""
from __future__ import annotations

import hashlib
import importlib.util
import inspect
import os
import sys
import time as _time
from pathlib import Path

import numpy as np

from .guarded import MAX_TIME
from .instances import CoSimulationError
from .system import split_signal


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
    writes its outputs to: inputs first) and ``modules`` (the kernel modules its source
    calls, imported under their last name), and builds in ``__init__`` its :attr:`arrays`
    (model arrays the kernel steps, shared with the slave's model objects).  :meth:`emit`
    returns the source lines of one step.

    Parameters
    ----------
    name : str
        The instance.
    slave : fmus.guarded.GuardedSlave
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
    modules: tuple = ()

    def __init__(self, name: str, slave, h: float):
        self.name, self.slave, self.h = name, slave, h
        self.arrays: list = []

    def emit(self, arrays: list, x: str, t: str, h: str) -> list:
        """Source lines of one step that set ``st`` to the status (0: done).

        ``arrays`` are the names of :attr:`arrays` in the generated function, ``x`` that of
        the I/O array, ``t`` the step's start time and ``h`` its length (expressions).
        """
        raise NotImplementedError

    def to_python(self) -> None:
        """Put state the kernel keeps outside the slave's objects back into them (before
        the Python path takes a step)."""

    def from_python(self) -> None:
        """Take state back from the slave's objects (after the Python path took a step)."""


#: What the adapters' kernel module names (``"plant.fast5r"``) are relative to: "" here, the
#: bundle's package inside an FMU (fmus/bundle.py), whose ``plant`` is its own.
_PACKAGE_ROOT = __name__[:-len("fmus.compiled")]


def _module_text(name: str) -> str:
    return inspect.getsource(importlib.import_module(_PACKAGE_ROOT + name))


def cache_dir() -> Path:
    """Where generated loops and numba's cache of them go: ``$PARCOSIM_COMPILED_CACHE`` or
    ``~/.cache/parcosim/compiled``."""
    return Path(os.environ.get("PARCOSIM_COMPILED_CACHE") or Path.home() / ".cache" / "parcosim" / "compiled")


class Plan:
    """The compiled loop of one system: adapters in stepping order, slots, generated source."""

    def __init__(self, system, stepper, instances):
        self.system, self.stepper = system, stepper
        entries = {id(inst): name for name, inst in instances.items()}
        self.adapters, self.positions = [], []   # positions: (group, member) of each adapter
        h = system.step
        for g, (substeps, members) in enumerate(stepper.groups):
            for m, (inst, _, _) in enumerate(members):
                name = entries[id(inst)]
                model = system.component(name).model
                cls = ADAPTERS.get(model)
                if cls is None:
                    raise NotCompilable(f"component {name}: model {model!r} has no compiled adapter")
                slave = inst.slave
                try:
                    slave.check_step_size(0.0, h / substeps)
                except ValueError as exc:
                    raise NotCompilable(f"component {name}: {exc}") from None
                adapter = cls(name, slave, h / substeps)
                in_names, out_names = stepper.io_names[name]
                for kind, names, known in (("input", in_names, cls.inputs), ("output", out_names, cls.outputs)):
                    unknown = [n for n in names if n not in known]
                    if unknown:
                        raise NotCompilable(f"component {name}: {kind}s {', '.join(unknown)} of {model} are not "
                                            "in its compiled adapter")
                adapter.x = np.array([float(getattr(slave, n)) for n in cls.inputs + cls.outputs])
                self.adapters.append(adapter)
                self.positions.append((g, m))
        self.source = self._generate()

    def _generate(self) -> str:
        stepper, system = self.stepper, self.stepper.system
        h = system.step
        params, lines, modules = [], [], set()
        by_position = dict(zip(self.positions, range(len(self.adapters))))
        for n, a in enumerate(self.adapters):
            params += [f"a{n}_{k}" for k in range(len(a.arrays))] + [f"x{n}"]
            modules.update(a.modules)
        body = ["    t = t0", "    for k in range(k0, k1):"]
        for g, (substeps, members) in enumerate(stepper.groups):
            dt = repr(h / substeps)
            indent = "        "
            if substeps > 1:
                body.append(f"{indent}for j in range({substeps}):")
                indent += "    "
                tstart = f"t + j * {dt}"
                sub = "j"
            else:
                tstart, sub = "t", "0"
            for m, (inst, in_slots, out_slots) in enumerate(members):
                n = by_position[(g, m)]
                a = self.adapters[n]
                in_names, out_names = stepper.io_names[a.name]
                layout = a.inputs + a.outputs
                body.append(f"{indent}# {a.name} ({a.model})")
                for name, slot in zip(in_names, in_slots):
                    body.append(f"{indent}x{n}[{layout.index(name)}] = values[{slot}]")
                arrays = [f"a{n}_{k}" for k in range(len(a.arrays))]
                body += [indent + line for line in a.emit(arrays, f"x{n}", tstart, dt)]
                body.append(f"{indent}if st != 0:")
                body.append(f"{indent}    return k, {n}, {sub}, t")
                for name, slot in zip(out_names, out_slots):
                    body.append(f"{indent}values[{slot}] = x{n}[{layout.index(name)}]")
        body.append("        t = t + h")
        for j, slot in enumerate(stepper.record_slots):
            body.append(f"        record[k + 1, {j}] = values[{slot}]")
        body.append("    return k1, -1, 0, t")
        imports = [f"from {_PACKAGE_ROOT}{m.rpartition('.')[0]} import {m.rpartition('.')[2]}"
                   for m in sorted(modules)]
        signature = ", ".join(params + ["values", "record", "k0", "k1", "t0", "h"])
        return "\n".join(['"""Generated by fmus.compiled: the step loop of one wiring (do not edit)."""',
                          "from numba import njit", *imports, "", "",
                          "@njit(cache=True, error_model=\"numpy\")", f"def run({signature}):",
                          *body, ""])

    def arguments(self) -> list:
        args = []
        for a in self.adapters:
            args += list(a.arrays) + [a.x]
        return args

    def load(self):
        """The compiled ``run`` of :attr:`source` (written, imported, compiled or loaded)."""
        modules = sorted({m for a in self.adapters for m in a.modules})
        digest = hashlib.sha256(self.source.encode())
        for m in modules:
            digest.update(_module_text(m).encode())
        key = digest.hexdigest()[:24]
        directory = cache_dir()
        directory.mkdir(parents=True, exist_ok=True)
        path = directory / f"loop_{key}.py"
        if not path.exists():
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(self.source)
            os.replace(tmp, path)
        name = f"parcosim_loop_{key}"
        module = sys.modules.get(name)
        if module is None:
            spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            sys.modules[name] = module
        return module.run


def _finish_step_in_python(stepper, start_group: int, start_member: int, start_substep: int, t: float) -> None:
    """The rest of the step from ``t`` in Python, from the given group, member and sub-step
    on (Gauss-Seidel, as :meth:`fmus.stepper.Stepper.step`)."""
    h, values = stepper.system.step, stepper.values
    for g, (substeps, members) in enumerate(stepper.groups):
        if g < start_group:
            continue
        dt = h / substeps
        for j in range(substeps):
            if g == start_group and j < start_substep:
                continue
            for m, (inst, in_slots, out_slots) in enumerate(members):
                if g == start_group and j == start_substep and m < start_member:
                    continue
                if in_slots:
                    inst.set_inputs([values[i] for i in in_slots])
                inst.do_step(t + j * dt if substeps > 1 else t, dt)
                for i, v in zip(out_slots, inst.get_outputs()):
                    values[i] = v
    stepper.time = t + h


def check_compilable(system, coupling: str, retry_substeps) -> None:
    """Raise :class:`NotCompilable` for what the compiled loop does not cover, before anything is built."""
    from .foreign import is_fmu_file

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
    from . import adapters  # noqa: F401 - registers the adapters of parcosim's models

    return ADAPTERS


def run_compiled(system, instances, order, progress, interrupt, result_of):
    """Initialise, compile and step; ``result_of(data, rows, error, interrupted, wall, init)``
    makes the :class:`fmus.master.Result`.  Raises :class:`NotCompilable` before the first
    step when a component's settings have no compiled loop."""
    from .stepper import Stepper

    _adapters()
    stepper = Stepper(system, instances, order)
    h, steps = system.step, system.steps
    data = np.full((steps + 1, len(system.record)), np.nan)
    init_start = _time.perf_counter()
    try:
        stepper.initialize(0.0)
    except CoSimulationError as exc:
        return result_of(data[:0], exc, False, 0.0, _time.perf_counter() - init_start, {})
    data[0] = stepper.row()
    plan = Plan(system, stepper, instances)
    compile_start = _time.perf_counter()
    run = plan.load()
    values = np.array(stepper.values, dtype=float)
    args = plan.arguments()
    run(*args, values.copy(), data[:1].copy(), 0, 0, 0.0, h)    # compile or load numba's cache
    compile_s = _time.perf_counter() - compile_start
    init_s = compile_start - init_start
    start, cpu_start = _time.perf_counter(), _time.thread_time()
    error, interrupted, done, t = None, False, 0, 0.0
    chunk = max(1, steps // 100)
    python_steps = 0
    try:
        while done < steps:
            if interrupt.requested:
                raise KeyboardInterrupt
            end = min(steps, done + chunk)
            k, n, sub, t = run(*args, values, data, done, end, t, h)
            done = k
            if n >= 0:     # a kernel declined step k: the Python path takes the rest of it
                for a in plan.adapters:
                    a.to_python()
                    a.slave._next_time = None   # the slaves did not see the compiled steps
                stepper.values[:] = values.tolist()
                g, m = plan.positions[n]
                _finish_step_in_python(stepper, g, m, sub, t)
                for a in plan.adapters:
                    a.from_python()
                values[:] = stepper.values
                t = stepper.time
                done = k + 1
                data[done] = stepper.row()
                python_steps += 1
            if progress is not None:
                progress(done / steps)
    except CoSimulationError as exc:
        error = exc
    except KeyboardInterrupt:
        interrupted = True
    wall = _time.perf_counter() - start
    extra = {"compile_s": compile_s, "python_steps": python_steps, "source": plan.source,
             "cpu_s": _time.thread_time() - cpu_start}
    return result_of(data[:done + 1], error, interrupted, wall, init_s, extra)
