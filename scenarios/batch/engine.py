"""Many scene runs as tasks on dask.distributed: the engine of ``parcosim sweep`` and ``parcosim report``.

Each run is one task (:func:`run_task`: :func:`scenarios.run.runner.run_scene` on a worker, its
metrics back); :func:`run_tasks` submits them to a cluster and hands each result to a
callback as it arrives, in completion order.  The cluster (:func:`open_client`): an existing
one with ``scheduler="tcp://host:8786"``, else a LocalCluster on this machine, one
single-threaded worker process per core by default (a run holds the GIL; threads would not
run in parallel).

Nothing is lost: a run that fails is a result carrying its error (``completed`` false,
``error`` the record of why, :class:`fmus.status.RunError`, of kind ``failed`` when the run could not start); a worker process that dies mid-run has its tasks rerun on another
worker by the scheduler (up to ``distributed.scheduler.allowed-failures`` times, then the
task's result is the KilledWorker error).

Worker processes start with the parent's ``sys.path`` minus the ``resources`` folders of FMUs
the parent ran in process (:mod:`scenarios.batch.worker_path`, a preload): they import the
installed parcosim, never an FMU's bundled copy of it.

Results are the same as a serial loop's, bit for bit: a task is a whole, deterministic run
in one process, and nothing it computes depends on where or when it runs.
"""
from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass

from fmus.status import RunStatus, RunError
from scenarios.batch import worker_path
from scenarios.scenes.scene import Scene

#: Metrics of a task that did not produce any (NaN where a number belongs).
_NO_METRICS = {"e_ef_mm": float("nan"), "tau_ef_Nm": float("nan"), "e_ss_mm": float("nan"),
               "e_ss_1s_mm": float("nan"), "t_settle_s": float("nan"), "settled": False,
               "completed": False, "wall_s": float("nan")}


@dataclass(frozen=True)
class Task:
    """One scene run.

    Parameters
    ----------
    key : str
        Unique among the tasks of one :func:`run_tasks` call (the dask key's prefix).
    scene : Scene
    mode : str
        :func:`fmus.cosim.master.simulate`'s mode.
    out_dir : str, optional
        Where the worker writes the run's files (result.csv, metrics.json, plots); None:
        no files, metrics only.  A path on the worker's machine.
    plots : bool
    """

    key: str
    scene: Scene
    mode: str = "inprocess"
    out_dir: str | None = None
    plots: bool = False


def run_task(task: Task) -> dict:
    """Run ``task`` (on a worker): its metrics (:func:`scenarios.run.metrics.scene_metrics`), or,
    when the run could not even start, ``completed`` false and ``error`` its record (kind ``failed``).  Never
    raises for a run that fails: the failure is the result."""
    from scenarios.run.runner import run_scene

    try:
        outcome = run_scene(task.scene, mode=task.mode, out_dir=task.out_dir, plots=task.plots)
    except Exception as exc:  # noqa: BLE001 - a run that cannot start is a result with its error
        return {**_NO_METRICS, "scene": task.scene.name, **_failed(exc)}
    return outcome.metrics


def _failed(exc: Exception) -> dict:
    """The metrics' ``outcome`` and ``error`` of a task that could not run (or whose worker died)."""
    error = RunError(RunStatus.FAILED, f"{type(exc).__name__}: {exc}")
    return {"outcome": error.kind.value, "error": error.record()}


def default_workers() -> int:
    """One worker per core (``os.cpu_count()``)."""
    return os.cpu_count() or 1


@contextlib.contextmanager
def open_client(scheduler: str | None = None, workers: int | None = None, processes: bool = True):
    """A dask ``Client``: connected to ``scheduler``, or to a new LocalCluster of ``workers``
    single-threaded workers (default :func:`default_workers`; ``processes=False``: threads of
    this process, for tests).  Closed (the cluster too) on leaving."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        if workers is not None:
            raise ValueError(f"workers = {workers!r}: the cluster at {scheduler} has its own workers")
        with Client(scheduler) as client:
            yield client
        return
    n = default_workers() if workers is None else workers
    if not (isinstance(n, int) and n >= 1):
        raise ValueError(f"workers = {workers!r} must be an integer >= 1")
    # A clean sys.path in each worker process: the preload is given by file, because importing
    # it by name would import the scenarios package (and fmus, through its aliases of moved
    # modules) from the path it is there to clean.
    preload = [worker_path.__file__] if processes else []
    with LocalCluster(n_workers=n, threads_per_worker=1, processes=processes, dashboard_address=":0",
                      silence_logs=40, preload=preload) as cluster, Client(cluster) as client:
        yield client


def run_tasks(tasks, client=None, scheduler=None, workers=None, on_result=None, progress=None,
              processes: bool = True) -> dict:
    """Run ``tasks`` on a cluster; return task key -> metrics (:func:`run_task`).

    Parameters
    ----------
    client : distributed.Client, optional
        Use this client's cluster (else :func:`open_client` with ``scheduler``, ``workers``,
        ``processes``).
    on_result : callable, optional
        ``on_result(task, metrics)`` in this process as each task finishes (completion order).
    progress : callable, optional
        ``progress(fraction)`` after each finished task.
    """
    tasks = list(tasks)
    keys = [t.key for t in tasks]
    if len(set(keys)) != len(keys):
        raise ValueError("task keys must be unique")
    if not tasks:
        if progress is not None:
            progress(1.0)
        return {}
    if client is None:
        with open_client(scheduler, workers, processes) as own:
            return run_tasks(tasks, client=own, on_result=on_result, progress=progress)
    from distributed import as_completed

    from fmus.cosim.foreign import is_fmu_file

    fmu_models = sorted({c.model for t in tasks if t.mode == "fmu" for c in t.scene.system.components
                         if not is_fmu_file(c.model)})
    if fmu_models:     # build stale FMUs once here, not in every worker at the same time
        from fmus.export.build import ensure_built

        ensure_built(fmu_models)
    futures = {client.submit(run_task, t, key=f"{t.key}-{os.urandom(4).hex()}", pure=False): t for t in tasks}
    results = {}
    try:
        for future in as_completed(futures):
            task = futures[future]
            try:
                metrics = future.result()
            except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: the task's row carries it
                metrics = {**_NO_METRICS, "scene": task.scene.name, **_failed(exc)}
            results[task.key] = metrics
            if on_result is not None:
                on_result(task, metrics)
            if progress is not None:
                progress(len(results) / len(tasks))
    finally:   # an interrupted call leaves no task running on a shared cluster
        pending = [f for f in futures if not f.done()]
        if pending:
            client.cancel(pending)
    return results
