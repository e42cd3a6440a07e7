"""Run an SSP package (``fmus.ssp.export.export_ssp``) in OSP libcosim (PyPI ``libcosimpy``).

libcosim, the Open Simulation Platform's co-simulation library, reads SSP 1.0 packages
itself (``libcosimpy`` wraps its C API ``libcosimc`` with ctypes):
``CosimExecution.from_ssp_file(path)`` unpacks the ``.ssp``, loads every component,
applies each component's parameter set and makes the connections.  What it needs and
does (measured and read in its sources: ``docs/ssp_tools.md``, "libcosim: what to
know"):

* **the step size**: ``from_ssp_file(path)`` without ``step_size`` takes its algorithm
  from an annotation of ``ssd:DefaultExperiment`` of type ``com.opensimulationplatform``
  (:func:`libcosim_annotation_xml`); without that annotation the process dies
  (segmentation fault: libcosimc builds the execution with no algorithm).
  ``from_ssp_file(path, step_size=ns)`` brings its own fixed-step algorithm instead;
* **parameters**: each component's *first* parameter binding is applied (all four
  types); libcosimc has no way to choose a set by name;
* **stepping**: the fixed-step algorithm is a Jacobi master at integer-nanosecond time
  points (``t = k h`` exactly); after ``fmi2ExitInitializationMode`` the outputs are
  passed to the inputs before the first step.  It steps the components on a pool of
  ``hardware_concurrency - 1`` worker threads unless the annotation gives
  ``numWorkerThreads``; ``0`` steps them on the calling thread;
* **errors**: fmi2Discard or fmi2Error from ``fmi2DoStep`` fails the step
  (``CosimExecution.step()`` returns False, no observer sees it).  An error in
  ``fmi2ExitInitializationMode`` on a worker thread terminates the process (the C++
  exception leaves a ``std::thread``: ``abort``); on the calling thread it fails the
  step like a refused one.
* **log**: libcosim prints its log to stdout, by default from level debug (every FMI
  Library call); ``libcosimpy.CosimLogging.log_output_level`` sets the level.

:func:`simulate_ssp_libcosim` runs a copy of the package whose annotation gives the
step size and ``numWorkerThreads="0"``, so that every FMU failure comes back as a
failed step (and the steps run 5-8 times faster than on one worker thread, see the doc).
"""
from __future__ import annotations

import contextlib
import ctypes
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import time as _time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np

from fmus.export.archive import rewrite
from fmus.ssp.export import NS, OSP_ANNOTATION, OSP_NS, _threads_text, libcosim_annotation, read_ssp_experiment
from fmus.ssp.run import SspRun, tool_refusal
from fmus.status import RunError, RunStatus
from fmus.cosim.system import split_signal

NS_PER_S = 1_000_000_000
LOG_LEVELS = ("trace", "debug", "info", "warning", "error", "fatal")

def _read_ssd(path) -> ET.Element:
    with zipfile.ZipFile(path) as zf:
        try:
            return ET.fromstring(zf.read("SystemStructure.ssd"))
        except KeyError:
            raise ValueError(f"{path}: no SystemStructure.ssd") from None


def _osp_step(ssd: ET.Element) -> tuple:
    for annotation in ssd.iterfind("ssd:DefaultExperiment/ssd:Annotations/ssc:Annotation", NS):
        if annotation.get("type") == OSP_ANNOTATION:
            el = annotation.find(f"{{{OSP_NS}}}Algorithm/{{{OSP_NS}}}FixedStepAlgorithm")
            if el is not None and el.get("baseStepSize") is not None:
                threads = el.get("numWorkerThreads")
                return float(el.get("baseStepSize")), (int(threads) if threads is not None else None)
    return None, None


def read_libcosim_step(path) -> tuple:
    """``(baseStepSize, numWorkerThreads)`` from the package's OSP annotation; ``None``
    for what it does not give (``(None, None)`` without the annotation)."""
    return _osp_step(_read_ssd(path))


def _set_annotation(ssd: ET.Element, step: float, worker_threads: int | None) -> None:
    """Replace (or add) the OSP annotation of ``ssd:DefaultExperiment``, in place."""
    experiment = ssd.find("ssd:DefaultExperiment", NS)
    if experiment is None:
        # SSP 1.0 order: System, Enumerations, Units, DefaultExperiment, Annotations.
        experiment = ET.Element(f"{{{NS['ssd']}}}DefaultExperiment")
        later = [i for i, c in enumerate(ssd) if c.tag == f"{{{NS['ssd']}}}Annotations"]
        ssd.insert(later[0] if later else len(ssd), experiment)
    annotations = experiment.find("ssd:Annotations", NS)
    if annotations is None:
        annotations = ET.SubElement(experiment, f"{{{NS['ssd']}}}Annotations")
    for old in annotations.findall("ssc:Annotation", NS):
        if old.get("type") == OSP_ANNOTATION:
            annotations.remove(old)
    annotations.append(libcosim_annotation(step, worker_threads))


def with_libcosim_annotation(path, out, step: float | None = None, worker_threads: int | None = None) -> Path:
    """Copy the package ``path`` to ``out`` with the OSP annotation set to ``step``
    (default: the package's communication step, ``fmus.ssp.export.read_ssp_experiment``) and
    ``worker_threads``.  ``out`` ending in ``.ssp`` is written as a package, anything
    else is a directory the package is unpacked into (libcosim loads either)."""
    if step is None:
        step = read_ssp_experiment(path)[2]
        if step is None:
            raise ValueError(f"{path}: the package gives no communication step; pass step")
    ssd = _read_ssd(path)
    _set_annotation(ssd, step, worker_threads)
    ET.indent(ssd)
    text = ET.tostring(ssd, encoding="UTF-8", xml_declaration=True) + b"\n"
    out = Path(out)
    with zipfile.ZipFile(path) as zf:
        if out.suffix.lower() == ".ssp":
            rewrite(path, out, {"SystemStructure.ssd": text})
        else:
            out.mkdir(parents=True, exist_ok=True)
            zf.extractall(out)
            (out / "SystemStructure.ssd").write_bytes(text)
    return out


# --- running ----------------------------------------------------------------------------------

def libcosim_available() -> str | None:
    """None when libcosimpy imports and loads its ``libcosimc``; otherwise why not."""
    try:
        from libcosimpy._internal import libcosimc

        libcosimc()
    except Exception as exc:  # noqa: BLE001 - ImportError, OSError for the shared library
        return f"{type(exc).__name__}: {exc}"
    return None


def set_libcosim_log_level(level: str = "warning") -> None:
    """libcosim's log level for the whole process: ``trace``, ``debug`` (its default:
    every FMI Library call), ``info``, ``warning``, ``error`` (FMU error messages are
    logged at this level), ``fatal``.  The log goes to stdout."""
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    name = {"warn": "warning"}.get(level.lower(), level.lower())
    if name not in LOG_LEVELS:
        raise ValueError(f"log level {level!r}: one of {', '.join(LOG_LEVELS)}")
    log_output_level(CosimLogLevel[name.upper()])


def _real_samples(observer, slave: int, reference: int, count: int):
    """(values, times [ns]) a time-series observer holds from step 0 on.  (libcosimpy's
    ``time_series_real_samples`` trims its result by the number of step numbers equal to
    0, so it drops the last sample when step 0 is among them.)"""
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy._internal import get_last_error_message, libcosimc, wrap_function

    values = (ctypes.c_double * count)()
    steps = (ctypes.c_int64 * count)()
    times = (ctypes.c_int64 * count)()
    get = wrap_function(lib=libcosimc(), funcname="cosim_observer_slave_get_real_samples",
                        argtypes=[ctypes.POINTER(CosimObserver), ctypes.c_int, ctypes.c_uint32, ctypes.c_int64,
                                  ctypes.c_size_t, ctypes.c_double * count, ctypes.c_int64 * count,
                                  ctypes.c_int64 * count],
                        restype=ctypes.c_int64)
    n = get(observer.ptr(), slave, reference, 0, count, values, steps, times)
    if n < 0:
        raise RuntimeError(f"libcosim has no samples: {get_last_error_message()}")
    return np.array(values[:n]), np.array(times[:n], dtype=np.int64)


def _experiment(path, ssd, stop_time, step_size):
    _, stop, step = read_ssp_experiment(path)
    if step is None:
        step = _osp_step(ssd)[0]
    stop_time = stop if stop_time is None else stop_time
    step_size = step if step_size is None else step_size
    if stop_time is None or step_size is None:
        raise ValueError(f"{path}: give stop_time and step_size (the package does not)")
    step_size = float(step_size)
    if not step_size > 0:
        raise ValueError(f"step_size = {step_size!r} must be > 0")
    step_ns = round(step_size * NS_PER_S)
    if step_ns < 1 or abs(step_ns - step_size * NS_PER_S) > 1e-6 * step_ns:
        raise ValueError(f"step_size = {step_size!r} s is no whole number of nanoseconds (libcosim's time unit)")
    return float(stop_time), step_size, step_ns


def simulate_ssp_libcosim(path, signals, stop_time=None, step_size=None, log_level: str = "warning",
                          worker_threads: int | None = 0, isolated: bool = False) -> SspRun:
    """Run an SSP package in libcosim and record ``signals`` (``"instance.variable"``,
    Real) after initialisation (t = 0) and after every step, like
    :func:`fmus.ssp.run.simulate_ssp_ecos`.

    Parameters
    ----------
    path : str or Path
        The ``.ssp`` package.
    signals : list of str
        Real variables to record (any variable of an FMU, connector or not).
    stop_time, step_size : float, optional
        Default: the package's (``ssd:DefaultExperiment``, its communication-step
        annotation or libcosim's own OSP annotation).  The step must be a whole number
        of nanoseconds.
    log_level : str
        libcosim's log level, process-wide (:func:`set_libcosim_log_level`).
    worker_threads : int or None
        ``numWorkerThreads`` of libcosim's fixed-step algorithm.  0 (default): the FMUs
        step on the calling thread, where an FMU error in initialisation fails the step
        instead of aborting the process; None: libcosim's default pool.
    isolated : bool
        Run libcosim in a child Python process (same interpreter) and return its result:
        a crash of the process (e.g. ``worker_threads=None`` and an FMU error while
        initialising) becomes a RuntimeError here, naming the exit status and the last five
        lines the process wrote (stderr, else stdout).

    libcosim loads the package with ``CosimExecution.from_ssp_file`` (no ``step_size``):
    as it is when its OSP annotation already gives this step and ``worker_threads``
    (:func:`fmus.ssp.export.export_ssp` writes one with 0), else a copy unpacked into a
    temporary directory with the annotation set.  It applies each
    component's first parameter set and steps all components Jacobi-style.

    When an FMU refuses a step (fmi2Discard, fmi2Error, or an error while initialising)
    libcosim fails it; the run stops there, keeps the rows so far and says why in
    ``SspRun.error`` (:func:`fmus.ssp.run.tool_refusal`): the record of the first component
    (in the package's order) whose String output ``refusal`` is not empty (parcosim FMUs have
    one), else a record with libcosim's message and no instance (libcosim does not say whose
    FMU failed the step; kind ``initialisation`` when not even the state after initialisation
    was observed).  ``extra`` has
    ``load_s`` (unpack, load, instantiate), ``init_s`` (the first ``step()``: libcosim
    initialises the FMUs in it, then takes the first step), ``steps_s`` (the others).
    """
    if isolated:
        return _isolated(path, signals, stop_time=stop_time, step_size=step_size, log_level=log_level,
                         worker_threads=worker_threads)
    reason = libcosim_available()
    if reason is not None:
        raise RuntimeError(f"libcosimpy cannot be loaded ({reason}); pip install libcosimpy")
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy._internal import get_last_error_message

    _threads_text(worker_threads)
    stop_time, step_size, step_ns = _experiment(path, _read_ssd(path), stop_time, step_size)
    steps = int(round(stop_time / step_size))
    wanted = [split_signal(s) for s in signals]

    set_libcosim_log_level(log_level)
    start = _time.perf_counter()
    tmp = Path(tempfile.mkdtemp(prefix="parcosim_libcosim_"))
    error, first = None, None
    try:
        if _osp_step(_read_ssd(path)) == (step_size, worker_threads):
            package = Path(path)      # it carries what libcosim needs: loaded as it is
        else:
            package = with_libcosim_annotation(path, tmp / "package", step_size, worker_threads)
        execution = CosimExecution.from_ssp_file(str(package))
        slaves = {info.name.decode(): info.index for info in execution.slave_infos()}
        variables = {name: {v.name.decode(): v for v in execution.slave_variables(index)}
                     for name, index in slaves.items()}
        refs = []
        for instance, name in wanted:
            v = variables.get(instance, {}).get(name)
            if v is None:
                raise ValueError(f"{instance}.{name}: no such variable in {path}")
            if CosimVariableType(v.type) is not CosimVariableType.REAL:
                raise ValueError(f"{instance}.{name} is {CosimVariableType(v.type).name}, not a Real")
            refs.append((slaves[instance], v.reference))
        series = CosimObserver.create_time_series(buffer_size=steps + 1)
        execution.add_observer(series)
        for slave, reference in dict.fromkeys(refs):
            series.start_time_series(slave, reference, CosimVariableType.REAL)
        # A last-value observer exposes every variable for reading after each fmi2DoStep,
        # so the String outputs 'refusal' are fresh after a refused step (see _refusal).
        last = CosimObserver.create_last_value()
        execution.add_observer(last)
        loaded = _time.perf_counter()
        for k in range(steps):
            if not execution.step():
                message = get_last_error_message()
                error = _refusal(execution, slaves, variables, k * step_size, message)
                break
            if k == 0:
                first = _time.perf_counter()
        end = _time.perf_counter()
        data, times = [], np.empty(0, dtype=np.int64)
        for j, (slave, reference) in enumerate(refs):
            try:
                values, t = _real_samples(series, slave, reference, steps + 1)
            except RuntimeError:   # no sample at all: initialisation failed
                values, t = np.empty(0), np.empty(0, dtype=np.int64)
            data.append(values)
            if j == 0:
                times = t
        rows = min((len(d) for d in data), default=0)
        if error is not None and error.instance is None and first is None and refs and rows == 0:
            # Not even the state after initialisation was observed: it failed.
            error = tool_refusal(None, 0.0, "", f"libcosim could not initialise the FMUs: {message.strip()}",
                                 RunStatus.INITIALISATION)
        del execution, series, last
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    wall = _time.perf_counter() - start
    first = end if first is None else first
    return SspRun(time=times[:rows] / NS_PER_S, signals={s: data[j][:rows] for j, s in enumerate(signals)},
                  tool="libcosim", wall_s=wall, error=error,
                  extra={"load_s": loaded - start, "init_s": first - loaded, "steps_s": end - first,
                         "step_ns": step_ns, "worker_threads": worker_threads})


def _refusal(execution, slaves: dict, variables: dict, t: float, message: str) -> RunError:
    """The record of the step from t that failed (:func:`fmus.ssp.run.tool_refusal`): the first
    component's String output ``refusal`` that is not empty, else libcosim's message.  libcosim
    does not observe after a failed step, but it has read every exposed variable after each
    ``fmi2DoStep``, refused or not, and an observer added now observes at once: the values the
    FMUs hold after the refusal."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimObserver import CosimObserver

    with contextlib.suppress(Exception):
        observer = CosimObserver.create_last_value()
        execution.add_observer(observer)
        for name, index in sorted(slaves.items(), key=lambda item: item[1]):
            v = variables[name].get("refusal")
            if v is None or CosimVariableType(v.type) is not CosimVariableType.STRING:
                continue
            value = observer.last_string_values(index, [v.reference])[0]
            text = value.decode(errors="replace") if isinstance(value, bytes) else (value or "")
            if text:
                return tool_refusal(name, t, text, message)
    return tool_refusal(None, t, "", f"libcosim stopped at the step from t = {t:.6g} s: {message.strip()}")


# --- in a child process -----------------------------------------------------------------------

def _isolated(path, signals, **kwargs) -> SspRun:
    with tempfile.TemporaryDirectory(prefix="parcosim_libcosim_run_") as tmp:
        args, result = Path(tmp) / "args.pickle", Path(tmp) / "result.pickle"
        args.write_bytes(pickle.dumps((str(Path(path).resolve()), list(signals), kwargs)))
        env = dict(os.environ)
        root = str(Path(__file__).resolve().parents[2])
        env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        proc = subprocess.run([sys.executable, "-c", "from fmus.ssp.libcosim import _child; _child()",
                               str(args), str(result)], capture_output=True, text=True, env=env)
        if proc.stdout:
            sys.stdout.write(proc.stdout)
        if proc.stderr:
            sys.stderr.write(proc.stderr)
        if not result.exists():
            tail = "\n".join((proc.stderr or proc.stdout or "").strip().splitlines()[-5:])
            raise RuntimeError(f"libcosim's process ended with exit status {proc.returncode} before "
                               "it had a result" + (f": {tail}" if tail else ""))
        outcome = pickle.loads(result.read_bytes())
    if isinstance(outcome, BaseException):
        raise outcome
    # A crash while the child tears down, after it wrote the result, costs nothing.
    outcome.extra["exit_status"] = proc.returncode
    return outcome


def _child() -> None:
    """Entry point of :func:`_isolated`'s child process."""
    args, result = Path(sys.argv[1]), Path(sys.argv[2])
    path, signals, kwargs = pickle.loads(args.read_bytes())
    try:
        outcome = simulate_ssp_libcosim(path, signals, **kwargs)
    except Exception as exc:  # noqa: BLE001 - handed to the parent, which raises it
        outcome = exc
    result.write_bytes(pickle.dumps(outcome))
