"""The co-simulation master: a :class:`fmus.cosim.system.System` stepped at a fixed communication step.

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

The clock: one time base, t_k = t_0 + k h with k the integer count of steps taken (t_0 = 0),
computed from k and never summed, in Python and in the C loop alike
(:class:`fmus.cosim.stepper.Stepper`, kernels/src/loop.c, the native ClosedLoop); a multi-rate
group's sub-step j of step k starts at t_k + j h / n (a retried step's split sub-steps too), and
row k is labelled k h, the time its step k - 1 ended at (docs/master.md, "The clock").

How a run is laid out (one record each, no argument lists handed down): :func:`simulate` checks
its arguments and makes a :class:`fmus.cosim.context.RunContext`; ``_simulate`` decides what the
compiled loop cannot cover from the system alone (:func:`fmus.cosim.compiled.check_compilable`)
before anything is loaded, loads the instances once, checks the signals, orders and wires them
(:class:`fmus.cosim.stepper.Stepper`, whose plan is one :class:`fmus.cosim.stepper.Entry` per
instance) and initialises them once; then either the compiled loop steps them
(:class:`fmus.cosim.compiled.Plan`; a component whose settings it declines sends the run on in
Python from the same initialised instances) or ``_step_in_python`` does, one
:meth:`Stepper.step <fmus.cosim.stepper.Stepper.step>` and one row per step.  Either hands back an
:class:`fmus.cosim.context.Outcome` that ``_result`` turns into the :class:`Result`.  The
Gauss-Seidel loop itself exists once in Python (``Stepper.step``: the usual step, a retried
step's split one, the rest of a step a compiled kernel declined, Jacobi) and once in C
(kernels/src/loop.c).

A refused step (fmi2Discard/Error/Fatal, or an exception in process) stops the run;
:class:`Result` keeps the rows recorded so far and ``error`` (:class:`fmus.status.RunError`)
says which instance refused, at what time, with its own message (``str(error)``) and, from
the component's record, its kind and the refused quantity.  A KeyboardInterrupt (SIGINT)
stops it the same way: the rows recorded so far, ``error`` of kind ``interrupted``,
"interrupted at t = ...", ``interrupted`` true (an FMU interrupted inside a call refuses it
with a record of kind ``interrupted``, which counts as the interruption).
"""
from __future__ import annotations

import contextlib
import functools
import signal as _signal
import threading
import time as _time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from fmus.cosim.backends import CoSimulationError, InProcessInstance, _FmuInstance
from fmus.cosim.context import Outcome, RunContext
from fmus.cosim.stepper import Stepper
from fmus.cosim.system import System, split_signal
from fmus.status import RunError, RunStatus

MODES = ("fmu", "inprocess", "compiled")
COUPLINGS = ("gauss-seidel", "jacobi")
#: Up to this many components in one feedback loop the order is optimal (exhaustive);
#: larger loops keep the system's listing order where the samples allow.
EXHAUSTIVE_LIMIT = 16


class AlgebraicLoopError(ValueError):
    """Connections that need each other's value in the same step."""


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
    error: RunError | None = None   # why the run stopped early (str(): the message)
    stop_time: float = 0.0
    init_s: float = 0.0   # loading, instantiating, initialising (tables, designs)
    #: ``cpu_s``: CPU time of this thread in the stepping (steadier than wall_s on a shared
    #: machine); ``retried``; compiled mode: ``compile_s``, ``python_steps``, ``source``,
    #: or ``fallback``.
    extra: dict = field(default_factory=dict)
    interrupted: bool = False   # stopped by KeyboardInterrupt (SIGINT); ``error`` says when

    @property
    def status(self) -> RunStatus:
        """How the run ended: :attr:`RunStatus.COMPLETED`, or ``error``'s kind."""
        return RunStatus.COMPLETED if self.error is None else self.error.kind


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
    from fmus.cosim.foreign import is_fmu_file

    if mode not in MODES:
        raise ValueError(f"mode = {mode!r}; valid: {', '.join(MODES)}")
    ours = [c for c in system.components if not is_fmu_file(c.model)]
    for c in system.components:
        if is_fmu_file(c.model) and not Path(c.model).is_file():
            raise ValueError(f"component {c.name}: no FMU file {c.model}")
    paths = {}
    if mode == "fmu":
        from fmus.export.build import ensure_built

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
    mode : {"inprocess", "fmu", "compiled"}
        Slave objects called directly, the built FMUs through fmpy (built into
        ``fmu_dir``, default ``fmus/build``, when missing or older than the sources), or the
        slave objects' compiled kernels in one generated, compiled loop (:mod:`fmus.cosim.compiled`:
        the same rows as in process; ``Result.extra["compile_s"]``; systems it does not
        cover fall back to in process with a warning, ``Result.extra["fallback"]``).
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
    if mode not in MODES:
        raise ValueError(f"mode = {mode!r}; valid: {', '.join(MODES)}")
    with deferred_sigint() as interrupt:
        return _simulate(RunContext(system, mode, coupling, fmu_dir, progress, retry_substeps, interrupt))


class _Interrupt:
    """Whether a SIGINT arrived (:func:`deferred_sigint`)."""

    requested = False


@contextlib.contextmanager
def deferred_sigint():
    """While inside, the first SIGINT only sets ``requested`` on the object yielded (the
    master stops between steps, never inside an FMU's call, where a KeyboardInterrupt
    would reach the FMU's own Python); a second one raises KeyboardInterrupt at once.
    Outside the main thread, or under a handler other than Python's default, nothing changes."""
    interrupt = _Interrupt()
    if threading.current_thread() is not threading.main_thread() or \
            _signal.getsignal(_signal.SIGINT) is not _signal.default_int_handler:
        yield interrupt
        return

    def handler(signum, frame):
        if interrupt.requested:
            raise KeyboardInterrupt
        interrupt.requested = True

    _signal.signal(_signal.SIGINT, handler)
    try:
        yield interrupt
    finally:
        _signal.signal(_signal.SIGINT, _signal.default_int_handler)


def _simulate(run: RunContext) -> Result:
    """Load, check, initialise and step ``run``'s system; close the instances."""
    fallback = None
    if run.mode == "compiled":     # what the compiled loop does not cover, known before anything is loaded
        from fmus.cosim.compiled import NotCompilable, check_compilable

        try:
            check_compilable(run.system, run.coupling, run.retry_substeps)
        except NotCompilable as exc:
            fallback = str(exc)
    loading = _time.perf_counter()
    instances = _instantiate(run.system, "fmu" if run.mode == "fmu" else "inprocess", run.fmu_dir)
    loading_s = _time.perf_counter() - loading
    try:
        from fmus.cosim.foreign import without_missing_parameters

        system, skipped = without_missing_parameters(run.system, {n: set(i.variables) for n, i in instances.items()})
        _check_signals(system, instances)
        if skipped:
            warnings.warn(skipped, stacklevel=3)
        run = replace(run, system=system)
        order = (stepping_order(system, {n: inst.variables for n, inst in instances.items()})
                 if run.coupling == "gauss-seidel" else tuple(c.name for c in system.components))
        # In process, slaves with a compiled step take it (fmus.cosim.segments); a retried step
        # takes states of every instance each step, which the Python path keeps.
        kernels = None
        if run.mode == "inprocess" and run.retry_substeps is None:
            from fmus.cosim.segments import Segments as kernels
        stepper = Stepper(system, instances, order, jacobi=run.coupling == "jacobi", kernels=kernels)
        init_start = _time.perf_counter()
        try:
            stepper.initialize(0.0)
        except CoSimulationError as exc:
            outcome = Outcome(np.empty((0, len(system.record))), exc, init_s=_time.perf_counter() - init_start)
            return _result(run, order, outcome, loading_s)
        init_s = _time.perf_counter() - init_start
        if run.mode == "compiled" and fallback is None:
            outcome, fallback = _compiled(run, stepper)
        if run.mode != "compiled" or fallback is not None:
            outcome = _step_in_python(run, stepper)
        outcome.init_s = init_s
        if fallback is not None:
            # The settings an adapter declines are known only once the slaves are set up: the run
            # goes on in process from the same initialised instances (nothing loaded twice).
            warnings.warn(f"compiled mode: {fallback}; running in process instead", stacklevel=3)
            outcome.extra["fallback"] = fallback
            run = replace(run, mode="inprocess")
        return _result(run, order, outcome, loading_s)
    finally:
        _close(instances)


def _compiled(run: RunContext, stepper: Stepper) -> tuple:
    """(the :class:`Outcome` of the compiled loop, None), or (None, why not) when a component's
    settings have no compiled loop."""
    from fmus.cosim.compiled import NotCompilable, Plan, run_compiled

    compile_start = _time.perf_counter()
    try:
        plan = Plan(run.system, stepper)
    except NotCompilable as exc:
        return None, str(exc)
    compile_s = _time.perf_counter() - compile_start
    outcome = run_compiled(run, stepper, plan)
    outcome.extra = {"compile_s": compile_s, **outcome.extra}
    return outcome, None


def _result(run: RunContext, order, outcome: Outcome, loading_s: float) -> Result:
    """The :class:`Result` of ``outcome``, stopped by its error (a CoSimulationError) or not."""
    system, data = run.system, outcome.rows
    h, rows = system.step, len(data)
    run_error = run_error_of(outcome.error, outcome.interrupted, max(rows - 1, 0) * h)
    return Result(time=np.arange(rows) * h, signals={s: data[:, j] for j, s in enumerate(system.record)},
                  order=tuple(order), mode=run.mode, coupling=run.coupling, wall_s=outcome.wall_s, error=run_error,
                  stop_time=system.stop_time, init_s=loading_s + outcome.init_s, extra=outcome.extra,
                  interrupted=run_error is not None and run_error.kind is RunStatus.INTERRUPTED)


def run_error_of(error: CoSimulationError | None, interrupted: bool, last: float) -> RunError | None:
    """The :class:`RunError` of a run stopped by ``error`` (the component's record, or a bare
    refusal when it gave none) or by SIGINT (``interrupted``) with its last row at ``last`` [s];
    None when it was not stopped."""
    if error is None:
        return RunError(RunStatus.INTERRUPTED, f"interrupted at t = {last:.6g} s", time=last) if interrupted else None
    known = error.time == error.time      # NaN: a call with no time of its own (setting inputs)
    record = error.run_error or RunError(RunStatus.REFUSED, error.message)
    if record.kind is RunStatus.INTERRUPTED:
        message = f"interrupted at t = {last:.6g} s ({error.instance}: {error.message})"
    else:
        message = str(error) if known else f"{error.instance}: {error.message} at t = {last:.6g} s"
    time = record.time if record.time is not None else (error.time if known else last)
    return replace(record, message=message, instance=record.instance or error.instance, time=time)


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
                                        f"sub-steps after {exc.instance} refused the full step)",
                                        again.run_error) from None
    finally:
        stepper.free_state(state)


def _step_in_python(run: RunContext, stepper: Stepper) -> Outcome:
    """Step the initialised ``stepper`` to the stop time (or to a refusal or a SIGINT): each
    step one :meth:`Stepper.step` and its row."""
    system, progress, interrupt = run.system, run.progress, run.interrupt
    retried = []
    advance = stepper.step if run.retry_substeps is None else \
        functools.partial(_retrying_step, stepper, run.retry_substeps, retried)
    steps = system.steps
    data = np.full((steps + 1, len(system.record)), np.nan)
    data[0] = stepper.row()
    record, done, error, interrupted = stepper.recorder(data), 0, None, False
    report_every = max(1, steps // 100)
    start, cpu_start = _time.perf_counter(), _time.thread_time()
    try:
        for k in range(1, steps + 1):
            if interrupt.requested:
                raise KeyboardInterrupt
            advance()
            record(k)
            done = k
            if progress is not None and (k % report_every == 0 or k == steps):
                progress(k / steps)
    except CoSimulationError as exc:
        error = exc
    except KeyboardInterrupt:
        interrupted = True
    wall, cpu = _time.perf_counter() - start, _time.thread_time() - cpu_start
    stepper.release()
    extra = {"cpu_s": cpu, **({"retried": retried} if run.retry_substeps is not None else {})}
    return Outcome(data[:done + 1], error, interrupted, wall, extra=extra)
