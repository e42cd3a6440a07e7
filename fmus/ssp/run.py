"""Run an SSP package (:mod:`fmus.ssp.export`) with fmpy's SSP runner or with Ecos.

Both are Jacobi masters (every component reads the outputs all held at the step's start);
:func:`simulate_ssp_fmpy` and :func:`simulate_ssp_ecos` record a package's signals the way
:func:`fmus.cosim.master.simulate` records a system's, in an :class:`SspRun`.
:mod:`fmus.ssp.libcosim` does the same in libcosim; docs/ssp.md says what each tool
needs and does by default.

A run a component stopped says why as data, whatever the tool: ``SspRun.error`` is the
:class:`fmus.status.RunError` our master gives (:func:`tool_refusal`), read from the
component's String output ``refusal``; a foreign FMU without one gets a record of the kind,
the instance and the time where the tool tells them, with the tool's message
(docs/contract.md, "A package's run in another tool").
"""
from __future__ import annotations

import contextlib
import os
import shutil
import time as _time
import warnings
import zipfile
from dataclasses import dataclass, field, replace

import numpy as np

from fmus.cosim.backends import CoSimulationError
from fmus.cosim.master import run_error_of
from fmus.cosim.system import split_signal
from fmus.ssp.export import NS, PARAMETER_SET, _parse, read_ssp_experiment, read_ssp_parameters
from fmus.status import RunError, RunStatus


# --- running a package ----------------------------------------------------------------------

@dataclass
class SspRun:
    """What a run of an SSP package recorded.

    ``time[k]`` is the time the values ``signals[name][k]`` hold at (the end of the step
    that produced them; 0 for the values after initialisation).  ``error``: why the run
    stopped before its stop time (:func:`tool_refusal`), None when it did not.
    """

    time: np.ndarray
    signals: dict
    tool: str
    wall_s: float
    error: RunError | None = None
    extra: dict = field(default_factory=dict)

    def __getitem__(self, signal: str) -> np.ndarray:
        return self.signals[signal]


def tool_refusal(instance: str | None, time: float, refusal: str, message: str,
                 kind: RunStatus = RunStatus.REFUSED, named: str | None = None) -> RunError:
    """The :class:`RunError` of a package's run that a component stopped at the step from
    ``time`` [s].

    With the component's String output ``refusal`` (``refusal``, its JSON; every parcosim FMU
    has one): the record our master makes of it (:func:`fmus.cosim.master.run_error_of`: the
    same fields and message as ``simulate(...).error``), its instance the package's component
    ``instance`` (followed, for a system FMU, by the inner component the FMU names after its
    own instance name ``named``: default ``instance``, the name fmpy and libcosim give it).
    Without it (a foreign FMU, "" ): a record of ``kind``, ``instance`` (None when the tool
    does not say whose FMU failed) and ``time``, with the tool's ``message``; the model's
    fields (variable, value, unit, code, reason) are None.
    """
    record = RunError.from_json(refusal)
    if record is None:
        return RunError(kind, message.strip() or "no reason given", instance=instance, time=time)
    named = instance if named is None else named
    inner = record.instance[len(named):] if (record.instance or "").startswith(named + ".") else ""
    record = replace(record, instance=instance + inner)
    return run_error_of(CoSimulationError(instance, time, record.message, record), False, time)


def _experiment(path, stop_time, step_size):
    _, stop, step = read_ssp_experiment(path)
    stop_time = stop if stop_time is None else stop_time
    step_size = step if step_size is None else step_size
    if stop_time is None or step_size is None:
        raise ValueError(f"{path}: give stop_time and step_size (the package does not)")
    if not step_size > 0:
        raise ValueError(f"step_size = {step_size!r} must be > 0")
    return float(stop_time), float(step_size)


def fmpy_parameter_set(path):
    """The package's parameter bindings as an ``fmpy.ssp.ssd.ParameterSet`` for
    ``simulate_ssp(..., parameter_set=...)``: names ``"instance.variable"``, typed values
    (fmpy would take the XML string ``"false"`` for True)."""
    from fmpy.ssp.ssd import Parameter, ParameterSet

    pset = ParameterSet(name=PARAMETER_SET)
    for name, value in read_ssp_parameters(path).items():
        type_ = {bool: "Boolean", int: "Integer", float: "Real", str: "String"}[type(value)]
        pset.parameters.append(Parameter(name=name, type=type_, value=value))
    return pset


@contextlib.contextmanager
def fmpy_watch():
    """Watch fmpy's SSP runner for the time of one run (module globals of
    ``fmpy.ssp.simulation``, restored afterwards) without changing what it does: yield a
    :class:`FmpyWatch` that knows each component instantiated and the call that raised."""
    import fmpy.ssp.simulation as sim

    originals = sim.instantiate_fmu, sim.do_step
    original_inst, original_step = originals
    watch = FmpyWatch()

    def instantiate_fmu(component, *args, **kwargs):
        watch.components[component.name] = component
        watch.call = (component.name, 0.0, RunStatus.INITIALISATION)
        original_inst(component, *args, **kwargs)

    def do_step(component, time, step_size):
        watch.call = (component.name, time, RunStatus.REFUSED)
        original_step(component, time, step_size)

    sim.instantiate_fmu, sim.do_step = instantiate_fmu, do_step
    try:
        yield watch
    finally:
        sim.instantiate_fmu, sim.do_step = originals


@dataclass
class FmpyWatch:
    """What :func:`fmpy_watch` saw: the components by name, and (instance, time, kind) of the
    last FMU call it watched (instantiation and initialisation, or a step)."""

    components: dict = field(default_factory=dict)
    call: tuple = (None, 0.0, RunStatus.INITIALISATION)

    def refusal(self, exc: BaseException) -> RunError:
        """The record of the run ``exc`` stopped (:func:`tool_refusal`: the refusing component's
        output ``refusal``, else fmpy's message); fmpy leaves the FMUs instantiated when it
        raises: this frees them."""
        instance, time, kind = self.call
        component = self.components.get(instance)
        text = _fmpy_string(component, "refusal") if component is not None else ""
        error = tool_refusal(instance, time, text, str(exc), kind)
        for component in self.components.values():
            with contextlib.suppress(Exception):
                component.fmu.terminate()
            with contextlib.suppress(Exception):
                component.fmu.freeInstance()
            shutil.rmtree(getattr(component, "unzipdir", None) or "", ignore_errors=True)
        return error

    def signals(self) -> dict:
        """Every connector (``"instance.connector"``) with no values: the rows fmpy lost."""
        return {f"{name}.{c.name}": np.empty(0) for name, component in self.components.items()
                for c in component.connectors}


def _fmpy_string(component, name: str) -> str:
    """The String output ``name`` of an fmpy SSP component; "" when it has none or it cannot be read."""
    variable = component.variables.get(name) if hasattr(component, "variables") else None
    if variable is None or variable.type != "String" or variable.causality != "output":
        return ""
    try:
        value = component.fmu.getString([variable.valueReference])[0]
    except Exception:  # noqa: BLE001 - a failed read leaves the tool's message
        return ""
    return value.decode(errors="replace") if isinstance(value, bytes) else str(value or "")


@contextlib.contextmanager
def _fmpy_patches(path, initial_outputs: bool):
    """Additions to fmpy's SSP runner for the time of one run (module globals of
    ``fmpy.ssp.simulation``, restored afterwards), inside :func:`fmpy_watch` (yielded):

    * ``set_value`` also sets String variables (fmpy 0.3 raises "Unsupported type: String");
    * ``set_parameters`` matches "instance." exactly (fmpy's bare prefix match would give
      instance "drive" the parameters of "drive2" as well) and skips, with a warning, a
      bound parameter the FMU lacks (a replacement FMU; libcosim and Ecos skip it too);
    * with ``initial_outputs``, the first step reads the outputs after initialisation
      through the connections (fmpy starts every connector at 0.0).
    """
    import fmpy.ssp.simulation as sim

    with zipfile.ZipFile(path) as zf:
        ssd = _parse(zf, "SystemStructure.ssd")
    links = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
             for c in ssd.iterfind("ssd:System/ssd:Connections/ssd:Connection", NS)]
    started = [False]
    with fmpy_watch() as watch:
        originals = sim.set_value, sim.set_parameters, sim.instantiate_fmu, sim.do_step
        original_set, _, original_inst, original_step = originals
        components = watch.components

        def set_value(component, name, value):
            variable = component.variables[name]
            if variable.type == "String":
                component.fmu.setString([variable.valueReference], [str(value)])
            else:
                original_set(component, name, value)

        def set_parameters(component, parameter_set):
            # fmpy matches by bare prefix: "drive" would also take the parameters of "drive2".
            prefix = component.name + "."
            missing = []
            for parameter in parameter_set.parameters:
                if parameter.name.startswith(prefix):
                    name = parameter.name[len(prefix):]
                    if name in component.variables:
                        set_value(component, name, parameter.value)
                    else:
                        missing.append(name)
            if missing:   # a replacement FMU without them: skipped, as libcosim and Ecos do
                warnings.warn(f"{component.name}: its FMU has no {', '.join(missing)}; the bindings are skipped",
                              stacklevel=2)

        def instantiate_fmu(component, *args, **kwargs):
            original_inst(component, *args, **kwargs)
            if initial_outputs:
                for connector in component.connectors:
                    if connector.kind == "output":
                        connector.value = sim.get_value(component, connector.name)

        def do_step(component, time, step_size):
            if initial_outputs and not started[0]:
                started[0] = True
                for se, sc, ee, ec in links:
                    src = next(c for c in components[se].connectors if c.name == sc)
                    dst = next(c for c in components[ee].connectors if c.name == ec)
                    dst.value = src.value
            original_step(component, time, step_size)

        sim.set_value, sim.set_parameters, sim.instantiate_fmu, sim.do_step = (
            set_value, set_parameters, instantiate_fmu, do_step)
        try:
            yield watch
        finally:
            sim.set_value, sim.set_parameters, sim.instantiate_fmu, sim.do_step = originals


def simulate_ssp_fmpy(path, stop_time=None, step_size=None, initial_outputs: bool = True) -> SspRun:
    """Run an SSP package with ``fmpy.ssp.simulation.simulate_ssp``.

    fmpy's runner is a Jacobi master.  It ignores the package's parameter bindings (they
    are passed as its ``parameter_set``), cannot set String variables and starts every
    connector at 0.0; this function adds String support and, with ``initial_outputs``
    (default), lets the first step read the outputs after initialisation, as
    ``fmus.cosim.master.simulate(..., coupling="jacobi")`` does.  fmpy labels the values after
    the step from t to t + h with t; the returned times are t + h.  fmpy records no row
    for t = 0, and as it adds h to its time at every step it may take one step more than
    ``stop_time / h``.

    Returns every connector (``"instance.connector"``) as a signal.  fmpy raises when an
    FMU refuses a call (fmi2Discard, fmi2Error) and its rows are lost: then the run has no
    rows and ``error`` is the record of the refusal (:func:`tool_refusal`: the refusing
    component's output ``refusal``, else fmpy's message).
    """
    from fmpy.fmi1 import FMICallException
    from fmpy.ssp.simulation import simulate_ssp

    stop_time, step_size = _experiment(path, stop_time, step_size)
    pset = fmpy_parameter_set(path)
    start = _time.perf_counter()
    with _fmpy_patches(path, initial_outputs) as watch:
        try:
            rows = simulate_ssp(str(path), start_time=0.0, stop_time=stop_time, step_size=step_size,
                                parameter_set=pset)
        except Exception as exc:
            error = watch.refusal(exc)          # frees the FMUs
            if not isinstance(exc, FMICallException):
                raise
            return SspRun(time=np.empty(0), signals=watch.signals(), tool="fmpy",
                          wall_s=_time.perf_counter() - start, error=error)
    wall = _time.perf_counter() - start
    names = [n for n in rows.dtype.names if n != "time"]
    return SspRun(time=rows["time"] + step_size, signals={n: np.asarray(rows[n]) for n in names},
                  tool="fmpy", wall_s=wall, extra={"fmpy_time_labels": np.asarray(rows["time"])})


def ecos_available() -> str | None:
    """None when ``ecospy`` loads; otherwise why not (e.g. libtbb.so.12 missing)."""
    try:
        import ecospy  # noqa: F401
    except Exception as exc:  # noqa: BLE001 - OSError for a missing libtbb, ImportError ...
        return f"{type(exc).__name__}: {exc}"
    return None


@contextlib.contextmanager
def _one_cpu(enabled: bool):
    """Run the block with the calling thread bound to one CPU.  Ecos (C++17 parallel
    algorithms on oneTBB) sizes its thread pool from this mask when it first steps, so
    it steps the models on the calling thread; the mask is restored afterwards."""
    if not enabled or not hasattr(os, "sched_getaffinity"):
        yield
        return
    before = os.sched_getaffinity(0)
    os.sched_setaffinity(0, {min(before)})
    try:
        yield
    finally:
        os.sched_setaffinity(0, before)


def simulate_ssp_ecos(path, signals, stop_time=None, step_size=None, serial: bool = True,
                      log_level: str = "warn") -> SspRun:
    """Run an SSP package with Ecos (PyPI ``ecospy``) and record ``signals``
    (``"instance.variable"``, Real) after initialisation and after every step.

    Ecos applies a parameter set only when ``init`` names it: this passes
    :data:`PARAMETER_SET`.  Ecos is a Jacobi master that also passes the outputs after
    initialisation to the inputs before the first step.  ``serial`` (default) keeps Ecos
    on the calling thread (see :func:`_one_cpu`): Python FMUs stepped from TBB worker
    threads only take turns on the GIL.

    Ecos steps on after an FMU returns fmi2Discard; this run stops at the first step after
    which a component's String output ``refusal`` (every parcosim FMU has one) is not empty,
    keeps the rows recorded so far and says why in ``SspRun.error`` (:func:`tool_refusal`), as
    :func:`fmus.cosim.master.simulate` does.  A foreign FMU has no such output: Ecos does not
    say that it refused a step, and the run goes on; a failed initialisation or an exception
    of Ecos' step is a record with Ecos' message and no instance (Ecos does not say whose).
    """
    reason = ecos_available()
    if reason is not None:
        raise RuntimeError(f"ecospy cannot be loaded ({reason}); pip install ecospy and apt-get install libtbb12")
    from ecospy import EcosLib, EcosSimulation

    stop_time, step_size = _experiment(path, stop_time, step_size)
    steps = int(round(stop_time / step_size))
    ids = [f"{i}::{v}" for i, v in map(split_signal, signals)]
    data = np.full((steps + 1, len(ids)), np.nan)
    with zipfile.ZipFile(path) as zf:
        instances = {c.get("name"): c.get("source") for c in
                     _parse(zf, "SystemStructure.ssd").iterfind("ssd:System/ssd:Elements/ssd:Component", NS)}
    EcosLib.set_log_level(log_level)
    error, times = None, []
    start = _time.perf_counter()
    with _one_cpu(serial):
        sim = EcosSimulation(step_size, ssp_path=str(path))
        loaded = _time.perf_counter()
        try:
            if not sim.init(0.0, PARAMETER_SET):
                error = tool_refusal(None, 0.0, "", f"Ecos could not initialise {path}: {EcosLib.get_last_error()}",
                                     RunStatus.INITIALISATION)
            else:
                error = _ecos_steps(sim, instances, ids, data, times, steps, step_size)
                sim.terminate()
        finally:
            sim.free()
    wall = _time.perf_counter() - start
    rows = len(times)
    return SspRun(time=np.asarray(times), signals={s: data[:rows, j] for j, s in enumerate(signals)},
                  tool="ecos", wall_s=wall, error=error, extra={"load_s": loaded - start})


def _ecos_steps(sim, instances, ids, data, times, steps: int, step_size: float) -> RunError | None:
    """Record the initialised Ecos simulation ``sim`` after initialisation and after each step
    into ``data`` and ``times``, up to ``steps`` steps or the first refusal (its record).
    ``instances``: component -> its FMU's path in the package; Ecos instantiates an FMU under
    the path it unpacked it to (measured: ``<temporary folder>/resources/plant.fmu``)."""
    from ecospy import EcosLib

    watched = []
    for name in instances:
        with contextlib.suppress(Exception):  # a foreign FMU without a String output 'refusal'
            sim.get_string(f"{name}::refusal")
            watched.append(name)
    get, get_string = sim.get_real, sim.get_string
    data[0] = [get(i) for i in ids]
    times.append(sim.get_time())
    for k in range(steps):
        try:
            sim.step(1)
        except Exception as exc:  # noqa: BLE001 - whatever Ecos raises stops the run
            return tool_refusal(None, k * step_size, "", f"{exc} {EcosLib.get_last_error() or ''}")
        for name in watched:
            refusal = get_string(f"{name}::refusal")
            if refusal:
                recorded = RunError.from_json(refusal).instance or ""
                end = recorded.rfind("/" + instances[name])
                named = recorded[:end + 1 + len(instances[name])] if end >= 0 else recorded
                return tool_refusal(name, k * step_size, refusal, "", named=named)
        data[k + 1] = [get(i) for i in ids]
        times.append(sim.get_time())
    return None
