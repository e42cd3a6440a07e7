"""The master's back ends: one component instance, in process or as an FMU through fmpy.

:func:`fmus.cosim.master.simulate` (and the system FMUs of :mod:`fmus.systemfmu.cores`) talk to every
instance through the same few calls: ``variables`` (name -> :class:`Variable`), ``bind``
(the variables a step moves), ``initialize``, ``set_inputs``, ``do_step``,
``get_outputs``, ``close``, and the FMU state calls.  :class:`InProcessInstance` calls a
parcosim slave object directly, as pythonfmu would; :class:`FmuInstance` calls an FMU's
``fmi2*`` functions through fmpy with preallocated, typed buffers.
"""
from __future__ import annotations

import atexit
import ctypes
import functools
import importlib
import itertools
import operator
from dataclasses import dataclass
from pathlib import Path

from fmus.cosim.slots import attribute_pull, gathering_pull, span
from fmus.status import FmiStatus, RunError


class CoSimulationError(Exception):
    """A component refused a call; carries the instance, the time and its message, and, when
    the component said why as a record (a parcosim slave's String output ``refusal``), that
    record (``run_error``, :class:`fmus.status.RunError`: its kind, and for a model's refusal the
    variable, value, unit and code)."""

    #: Its message names the time (``kernels.timed``): a system FMU reporting it adds none.
    names_time = True

    def __init__(self, instance: str, time: float, message: str, run_error: RunError | None = None):
        super().__init__(f"{instance} refused the step from t = {time:.6g} s: {message}")
        self.instance, self.time, self.message, self.run_error = instance, time, message, run_error


@dataclass(frozen=True)
class Variable:
    """What the master needs to know of one FMU variable."""

    name: str
    vr: int
    type: str  # "Real", "Integer", "Boolean", "String"
    causality: str
    variability: str
    depends_on: tuple = ()  # inputs this output depends on directly (feedthrough)


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
    arrays: one FMI call per type moves all their values (in the variables' order).  The
    arguments are ctypes objects already (the count a ``c_size_t``), as :func:`_step_calls`'
    functions, which declare no argument types, need them."""

    def __init__(self, variables: list, dll, verb: str):
        self.n = len(variables)
        self.groups = []
        for kind in _CTYPES:
            positions = [k for k, v in enumerate(variables) if v.type == kind]
            if positions:
                vrs = (ctypes.c_uint * len(positions))(*[variables[k].vr for k in positions])
                values = (_CTYPES[kind] * len(positions))()
                self.groups.append((getattr(dll, f"fmi2{verb}{kind}"), vrs, values, ctypes.c_size_t(len(positions)),
                                    positions, _CONVERT[kind]))
        # All Real, in order (every parcosim FMU): no regrouping on the step's path.
        self.plain = len(self.groups) == 1 and self.groups[0][4] == list(range(self.n)) and \
            self.groups[0][5] is float


_double, _TRUE = ctypes.c_double, ctypes.c_int(1)
#: A status above it refuses the call (:func:`fmus.status.step_failed`), as a plain int for the step's path.
_WARNING = int(FmiStatus.WARNING)


def _step_calls(dll):
    """The library whose ``fmi2DoStep``, ``fmi2Set*`` and ``fmi2Get*`` the step path calls.

    For an FMU whose binary is parcosim's FMI wrapper (it exports ``WRAPPER_SYMBOL``; its
    functions hold no lock and call this interpreter's slave under the GIL), the same library
    through ``ctypes.PyDLL``: called with the GIL held (no release and re-acquisition around
    each call) and without fmpy's argument types (the callers pass ctypes objects): about
    15 % of a step of the bench scene through the FMUs.  Any other FMU: fmpy's library as it
    loaded it (``ctypes.CDLL``, the GIL released during the call).
    """
    from fmus.slave.base import WRAPPER_SYMBOL

    if not hasattr(dll, WRAPPER_SYMBOL):
        return dll
    direct = ctypes.PyDLL(dll._name)
    for kind in _CTYPES:
        for verb in ("Set", "Get"):
            getattr(direct, f"fmi2{verb}{kind}").restype = ctypes.c_int
    direct.fmi2DoStep.restype = ctypes.c_int
    return direct


#: componentEnvironment -> the messages list of the :class:`_FmuInstance` whose FMU logs with it.
_LOGS: dict = {}
_ENVIRONMENTS = itertools.count(1)
_LOGGER = []      # the one ctypes logger of every _FmuInstance (kept referenced)


def _log(environment, instance, status, category, message) -> None:
    """An FMU's log message (formatted: :func:`_format_messages`) to the messages of the
    instance whose ``componentEnvironment`` it carries; another FMU's (fmpy's own callbacks
    share the formatting proxy) to fmpy's printer."""
    messages = _LOGS.get(environment)
    if messages is None:
        from fmpy.fmi2 import printLogMessage

        printLogMessage(environment, instance, status, category, message)
    else:
        messages.append(message.decode(errors="replace") if isinstance(message, bytes) else str(message))


def _logger(logger_type):
    if not _LOGGER:
        _LOGGER.append(logger_type(_log))
    return _LOGGER[0]


def _format_messages(callbacks) -> None:
    """Route ``callbacks``' logger through fmpy's C proxy (fmpy.logging), which formats the
    message with its arguments: FMI 2.0's logger is printf-like and variadic, which a ctypes
    callback cannot read (a C FMU's ``logger(..., "%s", why)`` arrived as "%s", parcosim's
    wrapper's ``%`` as ``%%``).  The proxy keeps one logger for the process (the last one
    given to it: an fmpy call with its own logger in between takes it until the next
    instance): every instance's is :func:`_log`, which dispatches by ``componentEnvironment``.
    Without the proxy the format arrives as is."""
    try:
        from fmpy.logging import addLoggerProxy
    except Exception:  # noqa: BLE001 - fmpy without its logging library for this platform
        return
    addLoggerProxy(ctypes.byref(callbacks))


#: (FMU path, mtime) -> (model description, unzipped folder): an FMU is unzipped once per process;
#: the folders go when the process exits (:func:`_remove_unzipped`).
_UNZIPPED: dict = {}


def _remove_unzipped() -> None:
    """Remove every folder :func:`_unzipped` made (at exit: the libraries in them stay loaded
    until then).  Without it each FMU a process ran left its unzipped copy in the temp folder."""
    import shutil

    for _, folder in _UNZIPPED.values():
        shutil.rmtree(folder, ignore_errors=True)
    _UNZIPPED.clear()


atexit.register(_remove_unzipped)


def _unzipped(path: Path, name: str):
    """(model description, unzipped folder) of the FMI 2.0 co-simulation FMU ``path``."""
    from fmpy import extract, read_model_description

    key = (str(path), path.stat().st_mtime_ns)
    if key not in _UNZIPPED:
        md = read_model_description(str(path))
        if md.fmiVersion != "2.0" or md.coSimulation is None:
            raise ValueError(f"component {name}: {path} is not an FMI 2.0 co-simulation FMU "
                             f"(fmiVersion {md.fmiVersion})")
        _UNZIPPED[key] = (md, extract(str(path)))
    return _UNZIPPED[key]


class _FmuInstance:
    """One FMU instance through fmpy, with batched I/O (one call per type and direction)."""

    def __init__(self, path: Path, name: str):
        from fmpy import calloc, free
        from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

        path = Path(path)
        md, directory = _unzipped(path, name)
        self.name, self.path = name, path
        self.variables = _variables_from_model_description(md)
        self.messages = []
        self._start_time = 0.0
        self._fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory,
                              modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        # The callbacks must stay referenced for the instance's lifetime.
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = _logger(fmi2CallbackLoggerTYPE)
        self._callbacks.componentEnvironment = self._environment = next(_ENVIRONMENTS)
        _LOGS[self._environment] = self.messages
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        _format_messages(self._callbacks)
        self._fmu.instantiate(callbacks=self._callbacks, loggingOn=True)
        self._component = ctypes.c_void_p(self._fmu.component)
        self._calls = _step_calls(self._fmu.dll)
        self._do_step = self._calls.fmi2DoStep

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
        self._inputs = _Batch(inputs, self._calls, "Set")
        self._outputs = _Batch(outputs, self._calls, "Get")

    def set_inputs(self, values: list) -> None:
        batch = self._inputs
        for setter, vrs, array, n, positions, convert in batch.groups:
            if batch.plain:
                array[:] = values
            else:
                array[:] = [convert(values[k]) for k in positions]
            if setter(self._component, vrs, n, array) > _WARNING:
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
        if self._do_step(self._component, _double(t), _double(h), _TRUE) > _WARNING:
            raise CoSimulationError(self.name, t, self._string_output("error") or self._last_message()
                                    or "fmi2DoStep refused", self._refusal())

    def _string_output(self, name: str) -> str:
        """The String output ``name`` of a parcosim FMU (``error``, ``refusal``: the same as in
        process); "" when the FMU has none."""
        variable = self.variables.get(name)
        if variable is None or variable.type != "String" or variable.causality != "output":
            return ""
        try:
            value = self._fmu.getString([variable.vr])[0]
        except Exception:  # noqa: BLE001 - a failed read must not hide the refusal
            return ""
        return value.decode(errors="replace") if isinstance(value, bytes) else str(value or "")

    def _refusal(self) -> RunError | None:
        """The record of the FMU's refusal (its String output ``refusal``), or None."""
        return RunError.from_json(self._string_output("refusal"))

    def _last_message(self) -> str:
        """The FMU's last log message (a foreign FMU's refusal, or a call refused by parcosim's
        wrapper, which logs the message alone)."""
        return self.messages[-1] if self.messages else ""

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
            _LOGS.pop(self._environment, None)


class InProcessInstance:
    """One slave object of ``fmus/slaves`` called directly, as pythonfmu would.

    ``slave`` is the object; ``variables`` its :class:`Variable` dict (see
    :func:`slave_variables`); :meth:`initialize` sets parameters as an importer does.
    """

    def __init__(self, model: str, name: str):
        from fmus.slave.registry import SLAVES

        if model not in SLAVES:
            raise ValueError(f"component {name}: unknown model {model!r}; valid: {', '.join(SLAVES)}")
        # relative: inside an FMU this package is its bundle's (fmus/export/bundle.py)
        cls = getattr(importlib.import_module(f"..slaves.{SLAVES[model]}", __package__), model)
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
        from fmus.slave.base import attribute_reader, attribute_writer

        # What the slave's setters and getters do, with the names looked up once: attributes
        # set to the values, outputs read back as Python values of their type.  Bound per
        # instance, they shadow the methods below (no variables before bind).
        write = attribute_writer(type(self.slave), [v.name for v in inputs], [_CONVERT[v.type] for v in inputs])
        read = attribute_reader([v.name for v in outputs], [_CONVERT[v.type] for v in outputs])
        self.set_inputs = functools.partial(write, self.slave)
        self.get_outputs = functools.partial(read, self.slave)
        self._bound = (inputs, outputs)

    def step_calls(self, in_slots, out_slots) -> tuple:
        """:func:`fmus.cosim.stepper.member_calls` of this instance: its plain Real attributes moved
        without a Python call of its own (the inputs converted to float, as :meth:`set_inputs`
        does, in one dict update; the outputs read as the slave holds them, Reals), the slave's
        ``do_step`` called directly.  Variables of another type, or attributes with a setter or
        a dotted name, take :meth:`set_inputs` and :meth:`get_outputs`."""
        inputs, outputs = self._bound
        slave, cls = self.slave, type(self.slave)

        def plain(variables):
            return all(v.type == "Real" and "." not in v.name and not hasattr(getattr(cls, v.name, None), "__set__")
                       for v in variables)

        pull = None
        if in_slots:
            pull = (attribute_pull(vars(slave), [v.name for v in inputs], in_slots) if plain(inputs)
                    else gathering_pull(self.set_inputs, in_slots))
        if outputs and plain(outputs):
            out = out_slots[0] if len(out_slots) == 1 else span(out_slots)
            return pull, slave.do_step, operator.attrgetter(*(v.name for v in outputs)), slave, out, self
        return pull, slave.do_step, operator.call, self.get_outputs, span(out_slots), self

    def step_refused(self, t: float) -> CoSimulationError:
        """The error of a ``do_step`` the slave refused (returned False) at ``t``, with the
        slave's record (its output ``refusal``)."""
        return CoSimulationError(self.name, t, getattr(self.slave, "error", "") or "do_step refused",
                                 RunError.from_json(getattr(self.slave, "refusal", "")))

    def set_inputs(self, values: list) -> None:
        """Set the bound inputs to ``values``."""

    def get_outputs(self) -> list:
        """The bound outputs' values."""
        return []

    def do_step(self, t: float, h: float) -> None:
        try:
            ok = self.slave.do_step(t, h)
        except Exception as exc:  # noqa: BLE001
            raise CoSimulationError(self.name, t, str(exc)) from None
        if ok is False:
            raise self.step_refused(t)

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
        return self.slave.deserialize_fmu_state(data)

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
