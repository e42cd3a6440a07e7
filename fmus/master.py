"""The co-simulation master: a :class:`fmus.system.System` stepped at a fixed communication step.

Two back ends run the same system and give identical results:

* ``"fmu"``: the built FMUs through fmpy.  Each FMU file is extracted and its model
  description read once per process; each instance gets its value references and a
  preallocated ctypes buffer once, and every step makes one ``fmi2SetReal``, one
  ``fmi2DoStep`` and one ``fmi2GetReal`` call (fmpy's list-based convenience calls cost
  about a third of a step).
* ``"inprocess"``: the same slave classes (``fmus/slaves``) stepped directly, no FMI.

Couplings (``coupling``):

* ``"gauss-seidel"`` (default): components are stepped one after the other and each reads
  the outputs its sources hold at that moment.  The order (:func:`stepping_order`) comes
  from the connections and what the FMUs declare: an output of ``variability="discrete"``
  is a sample taken at the step's start and held over the step (derivator, observer,
  controller), so its readers step after it, in the same step; any other output is a
  value at the end of the producer's step, so a reader stepped before the producer reads
  it at the step's start, which is what a sampled component wants.  Among the orders
  that keep every sample in its step, the master picks one where the fewest connections
  read a continuous output already advanced to t + h (ties: the system's listing order).
  A loop of samples or of direct-feedthrough outputs has no such order: it is reported
  as an algebraic loop naming its connections.
* ``"jacobi"``: every component reads the outputs all components held at the step's
  start, then all step (what fmpy's SSP runner and Ecos do).

Multi-rate: a component with ``substeps = n`` is stepped n times per communication step,
each ``h / n``; consecutive components (in the stepping order) with the same n step
together and exchange their values at every sub-step (e.g. the drives and the plant at
0.25 ms while the sampled components stay at 1 ms); what they read from the others is held.

Recorded signals: row 0 holds the outputs after initialisation (t = 0), row k those after
the k-th step (t = k h): for a continuous output the value at t, for a sampled output the
sample held over [t - h, t].

A refused step (fmi2Discard/Error/Fatal, or an exception in process) stops the run;
:class:`Result` keeps the rows recorded so far and ``error`` says which instance refused,
at what time, with its own message.
"""
from __future__ import annotations

import ctypes
import importlib
import operator
import time as _time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .stepper import Stepper
from .system import System, split_signal

MODES = ("fmu", "inprocess")
COUPLINGS = ("gauss-seidel", "jacobi")
#: Up to this many components in one feedback loop the order is optimal (exhaustive);
#: larger loops keep the system's listing order where the samples allow.
EXHAUSTIVE_LIMIT = 16


class CoSimulationError(Exception):
    """A component refused a call; carries the instance, the time and its message."""

    def __init__(self, instance: str, time: float, message: str):
        super().__init__(f"{instance} refused the step from t = {time:.6g} s: {message}")
        self.instance, self.time, self.message = instance, time, message


class AlgebraicLoopError(ValueError):
    """Connections that need each other's value in the same step."""


@dataclass(frozen=True)
class Variable:
    """What the master needs to know of one FMU variable."""

    name: str
    vr: int
    type: str  # "Real", "Integer", "Boolean", "String"
    causality: str
    variability: str
    depends_on: tuple = ()  # inputs this output depends on directly (feedthrough)


class RecordedRun:
    """Signals by name (``run["plant.x"]``) and whether the run reached its end; a base of
    run results that have ``signals`` and ``error``."""

    def __getitem__(self, signal: str) -> np.ndarray:
        return self.signals[signal]

    @property
    def completed(self) -> bool:
        """True when the run reached its stop time."""
        return self.error is None


@dataclass
class Result(RecordedRun):
    """What a run produced: the recorded signals, and why it stopped early if it did."""

    time: np.ndarray
    signals: dict
    order: tuple
    mode: str
    coupling: str
    wall_s: float   # stepping, from the first communication point to the last
    error: str | None = None
    stop_time: float = 0.0
    init_s: float = 0.0   # loading, instantiating and initialising (tables, numba compilation)
    extra: dict = field(default_factory=dict)


# --- component back ends ----------------------------------------------------------------

_CONVERT = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


def _set_parameters(variables: dict, parameters: dict, setters: dict) -> None:
    """Set each parameter with the setter of its FMI type (``setters[type](vrs, values)``)."""
    for name, value in parameters.items():
        variable = variables[name]
        setters[variable.type]([variable.vr], [_CONVERT[variable.type](value)])


#: ctypes of the FMI 2.0 types a connection can carry (fmi2Boolean is an int).
_CTYPES = {"Real": ctypes.c_double, "Integer": ctypes.c_int, "Boolean": ctypes.c_int}


class _Batch:
    """The value references of some variables, grouped by type, with preallocated ctypes
    arrays: one FMI call per type moves all their values (in the variables' order)."""

    def __init__(self, variables: list, dll, verb: str):
        self.n = len(variables)
        self.groups = []
        for kind in _CTYPES:
            positions = [k for k, v in enumerate(variables) if v.type == kind]
            if positions:
                vrs = (ctypes.c_uint * len(positions))(*[variables[k].vr for k in positions])
                values = (_CTYPES[kind] * len(positions))()
                self.groups.append((getattr(dll, f"fmi2{verb}{kind}"), vrs, values, len(positions), positions,
                                    _CONVERT[kind]))
        # All Real, in order (every parcosim FMU): no regrouping on the step's path.
        self.plain = len(self.groups) == 1 and self.groups[0][4] == list(range(self.n)) and \
            self.groups[0][5] is float


class _FmuInstance:
    """One FMU instance through fmpy, with batched I/O (one call per type and direction)."""

    _extracted: dict = {}

    def __init__(self, path: Path, name: str):
        from fmpy import calloc, extract, free, read_model_description
        from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

        path = Path(path)
        key = (str(path), path.stat().st_mtime_ns)
        if key not in self._extracted:
            md = read_model_description(str(path))
            if md.fmiVersion != "2.0" or md.coSimulation is None:
                raise ValueError(f"component {name}: {path} is not an FMI 2.0 co-simulation FMU "
                                 f"(fmiVersion {md.fmiVersion})")
            self._extracted[key] = (md, extract(str(path)))
        md, directory = self._extracted[key]
        self.name, self.path = name, path
        self.variables = _variables_from_model_description(md)
        self.messages = []
        self._start_time = 0.0
        self._fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory,
                              modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        # The callbacks must stay referenced for the instance's lifetime.
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self._fmu.instantiate(callbacks=self._callbacks, loggingOn=True)
        self._component = self._fmu.component
        self._do_step = self._fmu.dll.fmi2DoStep

    def _log(self, component, instance, status, category, message):
        self.messages.append(message.decode(errors="replace") if isinstance(message, bytes) else str(message))

    def enter_initialization(self, parameters: dict, start_time: float) -> None:
        """Set up the experiment, enter initialisation mode and set ``parameters``."""
        from fmpy.fmi1 import FMICallException

        fmu = self._fmu
        self._start_time = start_time
        try:
            fmu.setupExperiment(startTime=start_time)
            fmu.enterInitializationMode()
            _set_parameters(self.variables, parameters, {"Real": fmu.setReal, "Integer": fmu.setInteger,
                                                         "Boolean": fmu.setBoolean, "String": fmu.setString})
        except FMICallException:
            raise CoSimulationError(self.name, start_time, self._last_message() or "initialisation failed") from None

    def exit_initialization(self) -> None:
        from fmpy.fmi1 import FMICallException

        try:
            self._fmu.exitInitializationMode()
        except FMICallException:
            raise CoSimulationError(self.name, self._start_time,
                                    self._last_message() or "initialisation failed") from None

    def initialize(self, parameters: dict, start_time: float) -> None:
        """Initialise with ``parameters`` and no inputs set."""
        self.enter_initialization(parameters, start_time)
        self.exit_initialization()

    def bind(self, inputs: list, outputs: list) -> None:
        """The :class:`Variable` lists that :meth:`set_inputs` and :meth:`get_outputs` move."""
        self._inputs = _Batch(inputs, self._fmu.dll, "Set")
        self._outputs = _Batch(outputs, self._fmu.dll, "Get")

    def set_inputs(self, values: list) -> None:
        batch = self._inputs
        for setter, vrs, array, n, positions, convert in batch.groups:
            if batch.plain:
                array[:] = values
            else:
                array[:] = [convert(values[k]) for k in positions]
            if setter(self._component, vrs, n, array) > 1:
                raise CoSimulationError(self.name, float("nan"), self._last_message() or "setting inputs failed")

    def get_outputs(self) -> list:
        batch = self._outputs
        if batch.plain:
            getter, vrs, array, n, _, _ = batch.groups[0]
            getter(self._component, vrs, n, array)
            return array[:]
        values = [None] * batch.n
        for getter, vrs, array, n, positions, convert in batch.groups:
            getter(self._component, vrs, n, array)
            for k, value in zip(positions, array):
                values[k] = convert(value)
        return values

    def do_step(self, t: float, h: float) -> None:
        if self._do_step(self._component, t, h, 1) > 1:
            raise CoSimulationError(self.name, t, self._error_output() or self._last_message() or "fmi2DoStep refused")

    def _error_output(self) -> str:
        """The String output ``error`` of a parcosim FMU: the same text as in process."""
        variable = self.variables.get("error")
        if variable is None or variable.type != "String" or variable.causality != "output":
            return ""
        try:
            value = self._fmu.getString([variable.vr])[0]
        except Exception:  # noqa: BLE001 - a failed read must not hide the refusal
            return ""
        return value.decode(errors="replace") if isinstance(value, bytes) else str(value or "")

    def _last_message(self) -> str:
        # parcosim slaves log "<instance>: <message>"; the error names the instance already.
        message = self.messages[-1] if self.messages else ""
        return message[len(self.name) + 2:] if message.startswith(f"{self.name}: ") else message

    def get_state(self):
        """The FMU's ``fmi2GetFMUstate`` (free it with :meth:`free_state`)."""
        return self._fmu.getFMUstate()

    def set_state(self, state) -> None:
        self._fmu.setFMUstate(state)

    def free_state(self, state) -> None:
        self._fmu.freeFMUstate(state)

    def serialize_state(self, state) -> bytes:
        return bytes(self._fmu.serializeFMUstate(state))

    def deserialize_state(self, data: bytes):
        return self._fmu.deSerializeFMUstate(data)

    def close(self) -> None:
        try:
            self._fmu.terminate()
        finally:
            self._fmu.freeInstance()


class InProcessInstance:
    """One slave object of ``fmus/slaves`` called directly, as pythonfmu would.

    ``slave`` is the object; ``variables`` its :class:`Variable` dict (see
    :func:`slave_variables`); :meth:`initialize` sets parameters as an importer does.
    """

    def __init__(self, model: str, name: str):
        from .registry import SLAVES

        if model not in SLAVES:
            raise ValueError(f"component {name}: unknown model {model!r}; valid: {', '.join(SLAVES)}")
        cls = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)
        self.name = name
        self.slave = cls(instance_name=name)
        self.variables = slave_variables(self.slave)

    def enter_initialization(self, parameters: dict, start_time: float) -> None:
        """Set up the experiment, enter initialisation mode and set ``parameters``."""
        slave = self.slave
        self._start_time = start_time
        try:
            slave.setup_experiment(start_time, None, None)
            slave.enter_initialization_mode()
            _set_parameters(self.variables, parameters, {"Real": slave.set_real, "Integer": slave.set_integer,
                                                         "Boolean": slave.set_boolean, "String": slave.set_string})
        except Exception as exc:  # noqa: BLE001 - as an importer sees an FMU's fatal error
            raise CoSimulationError(self.name, start_time, str(exc)) from None

    def exit_initialization(self) -> None:
        try:
            self.slave.exit_initialization_mode()
        except Exception as exc:  # noqa: BLE001
            raise CoSimulationError(self.name, self._start_time, str(exc)) from None

    def initialize(self, parameters: dict, start_time: float) -> None:
        """Initialise with ``parameters`` and no inputs set."""
        self.enter_initialization(parameters, start_time)
        self.exit_initialization()

    def bind(self, inputs: list, outputs: list) -> None:
        """The :class:`Variable` lists that :meth:`set_inputs` and :meth:`get_outputs` move."""
        # What the slave's setters and getters do, with the names looked up once:
        # attributes set to the values, outputs read back as Python values of their type.
        self._inputs = [(v.name, _CONVERT[v.type]) for v in inputs]
        converters = [_CONVERT[v.type] for v in outputs]
        getter = operator.attrgetter(*[v.name for v in outputs]) if outputs else None
        if not outputs:
            self._read = lambda slave: []
        elif len(outputs) == 1:
            convert = converters[0]
            self._read = lambda slave: [convert(getter(slave))]
        elif all(c is float for c in converters):
            self._read = lambda slave: [float(v) for v in getter(slave)]
        else:
            self._read = lambda slave: [c(v) for c, v in zip(converters, getter(slave))]

    def set_inputs(self, values: list) -> None:
        slave = self.slave
        for (name, convert), value in zip(self._inputs, values):
            setattr(slave, name, convert(value))

    def get_outputs(self) -> list:
        return self._read(self.slave)

    def do_step(self, t: float, h: float) -> None:
        try:
            ok = self.slave.do_step(t, h)
        except Exception as exc:  # noqa: BLE001
            raise CoSimulationError(self.name, t, str(exc)) from None
        if ok is False:
            raise CoSimulationError(self.name, t, getattr(self.slave, "error", "") or "do_step refused")

    def get_state(self) -> dict:
        """An independent copy of the slave's state (its ``fmi2GetFMUstate``)."""
        return self.slave._get_fmu_state()

    def set_state(self, state: dict) -> None:
        """Go back to ``state`` (its ``fmi2SetFMUstate``; the state stays valid)."""
        self.slave._set_fmu_state(state)

    def free_state(self, state) -> None:
        """Nothing to free: a state in process is a Python object."""

    def serialize_state(self, state) -> bytes:
        """``state`` as the bytes of ``fmi2SerializeFMUstate``."""
        return self.slave._fmu_state_to_bytes(state)

    def deserialize_state(self, data: bytes):
        """The state of ``fmi2DeSerializeFMUstate`` (set it with :meth:`set_state`)."""
        return self.slave._fmu_state_from_bytes(data)

    def close(self) -> None:
        self.slave.terminate()


def _variables_from_model_description(md) -> dict:
    """Name -> :class:`Variable` of an FMU's model description.  An output whose
    ``ModelStructure`` entry has no ``dependencies`` attribute, or that has no entry, depends
    on every input (FMI 2.0 §2.2.8); ``dependencies=""`` means on none."""
    inputs = tuple(v.name for v in md.modelVariables if v.causality == "input")
    dependencies = {}
    for unknown in md.outputs:
        listed = unknown.dependencies
        dependencies[unknown.variable.name] = inputs if listed is None else tuple(v.name for v in listed)
    return {v.name: Variable(v.name, v.valueReference, v.type, v.causality, v.variability,
                             dependencies.get(v.name, inputs) if v.causality == "output" else ())
            for v in md.modelVariables}


def slave_variables(slave) -> dict:
    """Name -> :class:`Variable` of a pythonfmu slave object (feedthrough from its class)."""
    feedthrough = getattr(type(slave), "feedthrough", {})
    result = {}
    for vr, v in slave.vars.items():
        causality = v.causality.name if v.causality is not None else "local"
        variability = v.variability.name if v.variability is not None else "continuous"
        result[v.name] = Variable(v.name, vr, type(v).__name__, causality, variability,
                                  tuple(feedthrough.get(v.name, ())))
    return result


# --- the stepping order -------------------------------------------------------------------

def stepping_order(system: System, variables: dict) -> tuple:
    """The Gauss-Seidel order of ``system``'s components (see the module docstring).

    ``variables`` maps each instance name to its :class:`Variable` dict.  Raises
    :class:`AlgebraicLoopError` when sampled or feedthrough outputs form a loop.
    """
    names = [c.name for c in system.components]
    index = {n: i for i, n in enumerate(names)}
    hard = {n: set() for n in names}      # hard[b] = components that must step before b
    soft = {}                              # (reader, source) -> connections preferring reader first
    hard_edges = {}
    for conn in system.connections:
        src, out = split_signal(conn.source)
        dst, _ = split_signal(conn.target)
        if src == dst:
            continue
        variable = variables[src][out]
        if variable.variability == "discrete" or variable.depends_on:
            hard[dst].add(src)
            hard_edges.setdefault((src, dst), []).append(conn)
        else:
            soft[(dst, src)] = soft.get((dst, src), 0) + 1
    _check_hard_loops(names, hard, hard_edges)
    if len(names) > EXHAUSTIVE_LIMIT:
        return _listing_order(names, hard)

    # best[mask] = (violated soft connections, order as listing indices) over placed sets
    best = {0: (0, ())}
    for mask in range(1 << len(names)):
        if mask not in best:
            continue
        cost, order = best[mask]
        for i, n in enumerate(names):
            if mask & (1 << i) or any(not mask & (1 << index[p]) for p in hard[n]):
                continue
            # A reader placed after its continuous source reads t + h: count those.
            added = sum(count for (reader, source), count in soft.items()
                        if reader == n and mask & (1 << index[source]))
            candidate = (cost + added, order + (i,))
            new = mask | (1 << i)
            if new not in best or candidate < best[new]:
                best[new] = candidate
    return tuple(names[i] for i in best[(1 << len(names)) - 1][1])


def _listing_order(names, hard):
    placed, order = set(), []
    while len(order) < len(names):
        n = next(n for n in names if n not in placed and hard[n] <= placed)
        placed.add(n)
        order.append(n)
    return tuple(order)


def _check_hard_loops(names, hard, hard_edges):
    state = {}

    def visit(n, path):
        state[n] = 1
        for p in sorted(hard[n]):
            if state.get(p) == 1:
                cycle = path[path.index(p):] + [p] if p in path else [p, n]
                links = []
                for a, b in zip(cycle, cycle[1:]):
                    for conn in hard_edges.get((b, a), ()):
                        links.append(f"{conn.source} -> {conn.target}")
                raise AlgebraicLoopError(
                    "algebraic loop: these connections need each other's value within one step "
                    "(sampled or direct-feedthrough outputs): " + "; ".join(links))
            if state.get(p) is None:
                visit(p, path + [p])
        state[n] = 2

    for n in names:
        if n not in state:
            visit(n, [n])


# --- running -----------------------------------------------------------------------------

def _instantiate(system: System, mode: str, fmu_dir):
    """Instance name -> back-end instance: our components in process or as our built FMUs
    (by ``mode``), components given as an FMU file through fmpy in either mode."""
    from .foreign import is_fmu_file

    if mode not in MODES:
        raise ValueError(f"mode = {mode!r}; valid: {', '.join(MODES)}")
    ours = [c for c in system.components if not is_fmu_file(c.model)]
    for c in system.components:
        if is_fmu_file(c.model) and not Path(c.model).is_file():
            raise ValueError(f"component {c.name}: no FMU file {c.model}")
    paths = {}
    if mode == "fmu":
        from .build import ensure_built

        paths = ensure_built(sorted({c.model for c in ours}), fmu_dir)
    instances = {}
    try:
        for c in system.components:
            if is_fmu_file(c.model):
                instances[c.name] = _FmuInstance(Path(c.model), c.name)
            elif mode == "fmu":
                instances[c.name] = _FmuInstance(paths[c.model], c.name)
            else:
                instances[c.name] = InProcessInstance(c.model, c.name)
    except BaseException:
        _close(instances)
        raise
    return instances


def _close(instances: dict) -> None:
    for inst in instances.values():
        try:
            inst.close()
        except Exception:  # noqa: BLE001 - closing must not hide the run's outcome
            pass


#: Types a connection can carry (and a recorded signal can have).
CONNECTABLE = ("Real", "Integer", "Boolean")


def _check_signals(system: System, instances: dict) -> None:
    def variable(signal, causalities):
        instance, name = split_signal(signal)
        variables = instances[instance].variables
        if name not in variables:
            model = system.component(instance).model
            kinds = {}
            for v in variables.values():
                kinds.setdefault(v.causality, []).append(v.name)
            listing = "; ".join(f"{kind} {', '.join(names)}" for kind, names in kinds.items())
            raise ValueError(f"{signal}: {model} has no variable {name!r}; its variables: {listing}")
        v = variables[name]
        if v.causality not in causalities:
            raise ValueError(f"{signal} is a {v.causality}, expected {' or '.join(causalities)}")
        if v.type not in CONNECTABLE:
            raise ValueError(f"{signal} is {v.type}; only {', '.join(CONNECTABLE)} signals can be connected "
                             "or recorded")
        return v

    for conn in system.connections:
        source, target = variable(conn.source, ("output",)), variable(conn.target, ("input",))
        if source.type != target.type:
            raise ValueError(f"{conn.source} ({source.type}) -> {conn.target} ({target.type}): a connection "
                             "joins variables of one type")
    for signal in system.record:
        variable(signal, ("output", "input", "local"))
    for c in system.components:
        for name in c.parameters:
            v = instances[c.name].variables.get(name)
            if v is None or v.causality not in ("parameter", "input"):
                raise ValueError(f"component {c.name}: {c.model} has no parameter {name!r}")


def simulate(system: System, mode: str = "inprocess", coupling: str = "gauss-seidel",
             fmu_dir=None, progress=None, retry_substeps: int | None = None) -> Result:
    """Run ``system`` from 0 to its stop time.

    Parameters
    ----------
    system : System
    mode : {"inprocess", "fmu"}
        Slave objects called directly, or the built FMUs through fmpy (built into
        ``fmu_dir``, default ``fmus/build``, when missing or older than the sources).
    coupling : {"gauss-seidel", "jacobi"}
    progress : callable, optional
        Called as ``progress(fraction)`` about a hundred times during the run.
    retry_substeps : int, optional
        On a refused step, set every instance back to the step's start (FMU state, taken
        before every step) and take the step again with the refusing instance in this many
        sub-steps, inputs held; the step is refused only if that refuses too.  Retried
        steps are listed in ``Result.extra["retried"]`` as (time, instance).  None
        (default): a refused step stops the run, and no state is taken.

    Returns
    -------
    Result
        Never raises for a refused step: ``Result.error`` says what happened and the
        rows recorded so far are kept.  Bad systems (unknown variables, algebraic loops)
        raise ValueError before anything runs.
    """
    if coupling not in COUPLINGS:
        raise ValueError(f"coupling = {coupling!r}; valid: {', '.join(COUPLINGS)}")
    if retry_substeps is not None and not (isinstance(retry_substeps, int) and retry_substeps >= 2):
        raise ValueError(f"retry_substeps = {retry_substeps!r} must be an integer >= 2 (or None: no retry)")
    loading = _time.perf_counter()
    instances = _instantiate(system, mode, fmu_dir)
    loading_s = _time.perf_counter() - loading
    try:
        from .foreign import without_missing_parameters

        system, skipped = without_missing_parameters(system, {n: set(i.variables) for n, i in instances.items()})
        _check_signals(system, instances)
        if skipped:
            warnings.warn(skipped, stacklevel=2)
        variables = {n: inst.variables for n, inst in instances.items()}
        order = (stepping_order(system, variables) if coupling == "gauss-seidel"
                 else tuple(c.name for c in system.components))
        return _run(system, instances, order, mode, coupling, progress, loading_s, retry_substeps)
    finally:
        _close(instances)


def _retrying_step(stepper: Stepper, substeps: int, retried: list) -> None:
    """One step; if an instance refuses it, the step again from its start with that
    instance in ``substeps`` sub-steps (the second refusal is the step's)."""
    state = stepper.state()
    try:
        try:
            stepper.step()
        except CoSimulationError as exc:
            stepper.restore(state)
            retried.append((stepper.time, exc.instance))
            try:
                stepper.step(split={exc.instance: substeps})
            except CoSimulationError as again:
                raise CoSimulationError(again.instance, again.time, f"{again.message} (also refused in {substeps} "
                                        f"sub-steps after {exc.instance} refused the full step)") from None
    finally:
        stepper.free_state(state)


def _run(system, instances, order, mode, coupling, progress, loading_s=0.0, retry_substeps=None) -> Result:
    stepper = Stepper(system, instances, order, jacobi=coupling == "jacobi")
    retried = []
    advance = stepper.step if retry_substeps is None else lambda: _retrying_step(stepper, retry_substeps, retried)
    h, steps = system.step, system.steps
    data = np.full((steps + 1, len(system.record)), np.nan)
    error, done, rows = None, 0, 0
    init_start = start = _time.perf_counter()
    try:
        stepper.initialize(0.0)
        start = _time.perf_counter()
        data[0] = stepper.row()
        rows = 1
        report_every = max(1, steps // 100)
        for k in range(steps):
            advance()
            data[k + 1] = stepper.row()
            done = k + 1
            rows = done + 1
            if progress is not None and done % report_every == 0:
                progress(done / steps)
    except CoSimulationError as exc:
        error = str(exc) if exc.time == exc.time else f"{exc.instance}: {exc.message} at t = {done * h:.6g} s"
    wall = _time.perf_counter() - start
    data = data[:rows]
    return Result(time=np.arange(rows) * h, signals={s: data[:, j] for j, s in enumerate(system.record)},
                  order=tuple(order), mode=mode, coupling=coupling, wall_s=wall, error=error,
                  stop_time=system.stop_time, init_s=loading_s + (start - init_start),
                  extra={"retried": retried} if retry_substeps is not None else {})
