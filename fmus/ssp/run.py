"""Run an SSP package (:mod:`fmus.ssp.export`) with fmpy's SSP runner or with Ecos.

Both are Jacobi masters (every component reads the outputs all held at the step's start);
:func:`simulate_ssp_fmpy` and :func:`simulate_ssp_ecos` record a package's signals the way
:func:`fmus.cosim.master.simulate` records a system's, in an :class:`SspRun`.
:mod:`fmus.ssp.libcosim` does the same in libcosim; docs/ssp.md says what each tool
needs and does by default.
"""
from __future__ import annotations

import contextlib
import os
import shutil
import time as _time
import warnings
import zipfile
from dataclasses import dataclass, field

import numpy as np

from fmus.ssp.export import NS, PARAMETER_SET, _parse, read_ssp_experiment, read_ssp_parameters
from fmus.cosim.system import split_signal


# --- running a package ----------------------------------------------------------------------

@dataclass
class SspRun:
    """What a run of an SSP package recorded.

    ``time[k]`` is the time the values ``signals[name][k]`` hold at (the end of the step
    that produced them; 0 for the values after initialisation).
    """

    time: np.ndarray
    signals: dict
    tool: str
    wall_s: float
    error: str | None = None
    extra: dict = field(default_factory=dict)

    def __getitem__(self, signal: str) -> np.ndarray:
        return self.signals[signal]


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
def _fmpy_patches(path, initial_outputs: bool):
    """Additions to fmpy's SSP runner for the time of one run (module globals of
    ``fmpy.ssp.simulation``, restored afterwards):

    * ``set_value`` also sets String variables (fmpy 0.3 raises "Unsupported type: String");
    * ``set_parameters`` matches "instance." exactly (fmpy's bare prefix match would give
      instance "drive" the parameters of "drive2" as well) and skips, with a warning, a
      bound parameter the FMU lacks (a replacement FMU; libcosim and Ecos skip it too);
    * with ``initial_outputs``, the first step reads the outputs after initialisation
      through the connections (fmpy starts every connector at 0.0).
    """
    import fmpy.ssp.simulation as sim

    originals = sim.set_value, sim.set_parameters, sim.instantiate_fmu, sim.do_step
    original_set, _, original_inst, original_step = originals
    with zipfile.ZipFile(path) as zf:
        ssd = _parse(zf, "SystemStructure.ssd")
    links = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
             for c in ssd.iterfind("ssd:System/ssd:Connections/ssd:Connection", NS)]
    components, started = {}, [False]

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
        components[component.name] = component
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
        yield components
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
    FMU returns fmi2Discard and the rows are lost: this raises RuntimeError naming the
    component's ``error`` output.
    """
    from fmpy.ssp.simulation import simulate_ssp

    stop_time, step_size = _experiment(path, stop_time, step_size)
    pset = fmpy_parameter_set(path)
    start = _time.perf_counter()
    with _fmpy_patches(path, initial_outputs) as components:
        try:
            rows = simulate_ssp(str(path), start_time=0.0, stop_time=stop_time, step_size=step_size,
                                parameter_set=pset)
        except Exception as exc:
            # fmpy raises on fmi2Discard and leaves the FMUs instantiated: say who refused, free them.
            reasons = []
            for name, component in components.items():
                variable = component.variables.get("error")
                if variable is not None and variable.type == "String":
                    with contextlib.suppress(Exception):
                        message = component.fmu.getString([variable.valueReference])[0]
                        message = message.decode(errors="replace") if isinstance(message, bytes) else message
                        if message:
                            reasons.append(f"{name}: {message}")
                with contextlib.suppress(Exception):
                    component.fmu.terminate()
                with contextlib.suppress(Exception):
                    component.fmu.freeInstance()
                shutil.rmtree(getattr(component, "unzipdir", None) or "", ignore_errors=True)
            raise RuntimeError(f"fmpy's SSP runner stopped ({exc})"
                               + (": " + "; ".join(reasons) if reasons else "")) from exc
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
    which a component's String output ``error`` (every parcosim FMU has one) is not empty,
    keeps the rows recorded so far and says why in ``SspRun.error``, as
    :func:`fmus.cosim.master.simulate` does.
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
        instances = [c.get("name") for c in
                     _parse(zf, "SystemStructure.ssd").iterfind("ssd:System/ssd:Elements/ssd:Component", NS)]
    EcosLib.set_log_level(log_level)
    error, times = None, []
    start = _time.perf_counter()
    with _one_cpu(serial):
        sim = EcosSimulation(step_size, ssp_path=str(path))
        loaded = _time.perf_counter()
        try:
            if not sim.init(0.0, PARAMETER_SET):
                raise RuntimeError(f"Ecos could not initialise {path}: {EcosLib.get_last_error()}")
            watched = []
            for name in instances:
                with contextlib.suppress(Exception):  # an FMU without a String output 'error'
                    sim.get_string(f"{name}::error")
                    watched.append(name)
            get, get_string = sim.get_real, sim.get_string
            data[0] = [get(i) for i in ids]
            times.append(sim.get_time())
            for k in range(steps):
                sim.step(1)
                for name in watched:
                    message = get_string(f"{name}::error")
                    if message:
                        error = f"{name} refused the step from t = {k * step_size:.6g} s: {message}"
                        break
                if error:
                    break
                data[k + 1] = [get(i) for i in ids]
                times.append(sim.get_time())
            sim.terminate()
        finally:
            sim.free()
    wall = _time.perf_counter() - start
    rows = len(times)
    return SspRun(time=np.asarray(times), signals={s: data[:rows, j] for j, s in enumerate(signals)},
                  tool="ecos", wall_s=wall, error=error, extra={"load_s": loaded - start})
