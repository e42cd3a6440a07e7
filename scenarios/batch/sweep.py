"""Monte Carlo sweeps: N runs of a scene with its plant and drives perturbed, on dask.distributed.

``parcosim sweep SCENE --samples N --uncertainty U [--seed S] [--distribution uniform|normal]
[--perturb FILE.toml] [--mode M] [--scheduler ADDRESS] [--workers K] [--out DIR]`` is
:func:`run_sweep`::

    from scenarios.batch.sweep import run_sweep
    sweep = run_sweep("bench_circle_TCMDx", samples=100, uncertainty=0.2, out_dir="out/sweep")
    print(sweep.summary["e_ef_mm"]["median"], [r["e_ef_mm"] for r in sweep.rows][:3])

What is perturbed and how: :mod:`scenarios.scenes.perturb` (the controller side keeps its nominal
model).  Each sample is one task of :mod:`scenarios.batch.engine`.  ``U = 0`` runs the nominal
scene, bit for bit ``parcosim run SCENE`` with the same mode.

Files in DIR:

* ``sweep.csv``: one row per sample, in sample order: ``sample``, one column per
  perturbed parameter (its value), ``e_ef_mm``, ``tau_ef_Nm``, ``e_ss_mm`` (once settled),
  ``e_ss_1s_mm``, ``t_settle_s`` (:mod:`scenarios.run.metrics`), ``completed``, ``outcome``
  (:class:`fmus.status.RunStatus`), the fields of the error's record (:class:`fmus.status.RunError`)
  ``error_instance``, ``error_time``, ``error_variable``, ``error_value``, ``error_unit``,
  ``error_code``, ``error_reason`` (empty when the sample completed or the field is unknown;
  ``nan`` for ``error_time`` and ``error_value``; an empty one is read back as NaN too),
  ``error`` (its message), ``wall_s``.
  While the sweep runs, each row is appended and flushed to disk as its run finishes, in one
  write: a sweep killed at any point leaves every finished row whole (a torn last line, if
  any, is dropped when the sweep starts again); when it ends, the file is rewritten
  (atomically) in sample order.
* ``sweep.json``: the sweep's settings.  Started again with the same DIR and settings, the
  sweep computes only the samples missing from ``sweep.csv`` (also after raising N); other
  settings are refused, naming the one that differs.
* ``summary.json``, ``summary.md``: statistics of the metrics over the completed samples;
  ``sweep.png``: their violin and box plots.

A run that fails (a component refuses a step, a worker dies more often than the scheduler
retries) is a row with ``completed`` false, its ``outcome`` and its error's fields; it is not run again.
"""
from __future__ import annotations

import collections
import csv
import io
import json
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from fmus.status import RunStatus
from scenarios.batch.engine import Task, run_tasks
from scenarios.scenes.perturb import DISTRIBUTIONS, draw, load_perturb_file, perturbable, perturbed, uncertainties
from scenarios.run.runner import atomic_write, check_writable, write_json
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.scene import Scene

#: The metrics of a sweep row, then the bookkeeping columns.
#: e_ss_mm: once settled; t_settle_s NaN (empty in the summary's n) when a run did not settle.
METRICS = ("e_ef_mm", "tau_ef_Nm", "e_ss_mm", "e_ss_1s_mm", "t_settle_s")
#: The fields of the error's record (:meth:`fmus.status.RunError.record`) a row has as columns
#: ``error_<field>``; the message is the column ``error``.
ERROR_FIELDS = ("instance", "time", "variable", "value", "unit", "code", "reason")
TAIL = ("completed", "outcome", *(f"error_{f}" for f in ERROR_FIELDS), "error", "wall_s")
#: Columns read back as text; ``error_code`` as an integer; the others as floats.
_TEXT = frozenset(("outcome", "error_instance", "error_variable", "error_unit", "error_reason", "error"))
#: Settings that must match to continue a sweep in the same directory.
_SETTINGS = ("scene", "uncertainty", "seed", "distribution", "perturb", "mode", "stop_time", "parameters")


@dataclass
class Sweep:
    """What :func:`run_sweep` computed.

    Attributes
    ----------
    scene : str
    parameters : list of str
        The perturbed parameters (the csv's parameter columns), ``<instance>.<parameter>``.
    rows : list of dict
        One per sample 0..N-1, by sample: ``sample``, the parameter values, the metrics,
        ``completed`` (bool), ``outcome`` (str), the error's fields ``error_<field>`` (None, NaN or
        "" when unknown), ``error`` (its message, "" when none), ``wall_s``.
    summary : dict
        Metric -> statistics over the completed samples (:func:`summarize`).
    computed : list of int
        The samples run by this call (the others were in ``sweep.csv`` already).
    settings : dict
    files : list of Path
    """

    scene: str
    parameters: list
    rows: list
    summary: dict
    computed: list
    settings: dict
    files: list = field(default_factory=list)

    def column(self, name: str) -> np.ndarray:
        """The column ``name`` over the rows, as floats."""
        return np.array([float(r[name]) for r in self.rows])


def with_stop_time(scene: Scene, stop_time: float | None) -> Scene:
    """``scene`` ending at ``stop_time`` [s] (None: unchanged), for short checks: metric
    windows the run no longer reaches are NaN."""
    if stop_time is None:
        return scene
    if not (isinstance(stop_time, (int, float)) and 0.0 < stop_time <= scene.system.stop_time):
        raise ValueError(f"stop_time = {stop_time!r} s must be in (0, {scene.system.stop_time:g}] "
                         f"(the scene's own end)")
    return replace(scene, system=replace(scene.system, stop_time=float(stop_time)))


def columns(parameters: list) -> list:
    """The header of sweep.csv."""
    return ["sample", *parameters, *METRICS, *TAIL]


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return " ".join(str(value).split())      # one line per row, always


def error_columns(metrics: dict) -> dict:
    """A run's ``outcome`` and its error's record (``metrics["error"]``) as a row's columns."""
    error = metrics.get("error") or {}
    columns = {"outcome": metrics.get("outcome", "")}
    for name in ERROR_FIELDS:
        value = error.get(name)
        if name in ("time", "value"):
            value = math.nan if value is None else float(value)
        elif name != "code":
            value = "" if value is None else value
        columns[f"error_{name}"] = value
    columns["error"] = error.get("message", "")
    return columns


def _line(header: list, row: dict) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow([_cell(row[c]) for c in header])
    return buffer.getvalue()


def _parse(row: dict) -> dict:
    out = {}
    for key, text in row.items():
        if key == "sample":
            out[key] = int(text)
        elif key == "completed":
            out[key] = text == "true"
        elif key in _TEXT:
            out[key] = text
        elif key == "error_code":
            out[key] = int(text) if text else None
        elif key in ("error_time", "error_value") and not text:
            out[key] = math.nan
        else:
            out[key] = float(text)
    return out


def read_rows(path: Path, header: list, repair: bool = False) -> list:
    """The whole rows of an existing sweep.csv, without a torn last line; ``repair``: also cut
    that line off the file (only the sweep that continues the file may: a reader of a file
    being written would cut a row in the making).

    Raises
    ------
    ValueError
        The file's header is not ``header`` (another sweep's file).
    """
    raw = path.read_bytes()
    if not raw:
        return []
    end = raw.rfind(b"\n") + 1
    if end < len(raw) and repair:        # the process writing the last row was killed mid-write
        with open(path, "r+b") as f:
            f.truncate(end)
    raw = raw[:end]
    lines = raw.decode("utf-8").splitlines()
    if not lines:             # killed while writing the header
        return []
    found = next(csv.reader([lines[0]]))
    if found != header:
        raise ValueError(f"{path}: header {found} is not this sweep's {header}")
    return [_parse(dict(zip(header, values))) for values in csv.reader(lines[1:])]


class _Appender:
    """Appends rows to sweep.csv, one ``write`` and an fsync per row."""

    def __init__(self, path: Path, header: list):
        self.header = header
        fresh = not path.exists() or path.stat().st_size == 0
        self.fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        if fresh:
            self._write(",".join(header) + "\n")

    def _write(self, text: str) -> None:
        os.write(self.fd, text.encode("utf-8"))
        os.fsync(self.fd)

    def append(self, row: dict) -> None:
        self._write(_line(self.header, row))

    def close(self) -> None:
        os.close(self.fd)


def summarize(rows: list) -> dict:
    """Metric -> {"n", "mean", "std", "min", "p05", "median", "p95", "max"} over the completed
    rows with a finite value, "samples", "completed", "failed" counts ("failed": every sample
    not completed, whatever its outcome) and "outcomes": the count of each outcome
    (:class:`fmus.status.RunStatus`' word) among the rows, in that class' order."""
    done = [r for r in rows if r["completed"]]
    summary = {"samples": len(rows), "completed": len(done), "failed": len(rows) - len(done)}
    counts = collections.Counter(r["outcome"] for r in rows)
    summary["outcomes"] = {s.value: counts[s.value] for s in RunStatus if counts[s.value]}
    for metric in METRICS:
        v = np.array([r[metric] for r in done if math.isfinite(r[metric])])
        if not len(v):
            summary[metric] = {"n": 0}
            continue
        p05, median, p95 = np.percentile(v, [5, 50, 95])
        summary[metric] = {"n": int(len(v)), "mean": float(v.mean()), "std": float(v.std(ddof=1)) if len(v) > 1
                           else 0.0, "min": float(v.min()), "p05": float(p05), "median": float(median),
                           "p95": float(p95), "max": float(v.max())}
    return summary


def summary_markdown(sweep: Sweep) -> str:
    """summary.md: the settings, a table of the statistics (4 significant digits; a metric with
    no finite value has n = 0 and empty cells) and, when samples failed, the first 20 of them
    (``* <sample>: <error>``) in sample order."""
    s, st = sweep.summary, sweep.settings
    lines = [f"# Sweep of {sweep.scene}", "",
             f"U = {st['uncertainty']:g} ({st['distribution']}), seed {st['seed']}, mode {st['mode']}; "
             f"{s['samples']} samples, {s['completed']} completed, {s['failed']} failed; "
             f"{len(sweep.parameters)} perturbed parameters.", "",
             "| metric | n | mean | std | min | 5 % | median | 95 % | max |", "|---|---|---|---|---|---|---|---|---|"]
    for metric in METRICS:
        m = s[metric]
        if not m["n"]:
            lines.append(f"| {metric} | 0 | | | | | | | |")
            continue
        lines.append(f"| {metric} | {m['n']} | " + " | ".join(f"{m[k]:.4g}" for k in (
            "mean", "std", "min", "p05", "median", "p95", "max")) + " |")
    failed = [r for r in sweep.rows if not r["completed"]]
    if failed:
        lines += ["", "Failed samples:", ""] + [f"* {r['sample']}: {r['error']}" for r in failed[:20]]
    return "\n".join(lines) + "\n"


def _check_settings(path: Path, settings: dict) -> None:
    old = json.loads(path.read_text())
    for key in _SETTINGS:
        if old.get(key) != settings[key]:
            raise ValueError(f"{path.parent} holds a sweep with {key} = {old.get(key)!r}, not {settings[key]!r}: "
                             "continue it with the same settings, or use another --out")


def run_sweep(scene, samples: int, uncertainty: float, seed: int = 0, distribution: str | None = None,
              perturb=None, mode: str = "inprocess", out_dir=None, scheduler: str | None = None,
              workers: int | None = None, client=None, stop_time: float | None = None, progress=None,
              on_row=None, plots: bool = True, processes: bool = True) -> Sweep:
    """Run ``samples`` perturbed copies of ``scene`` (a name or a :class:`Scene`).

    Parameters
    ----------
    samples : int
        N: samples 0..N-1.
    uncertainty : float
        U, the relative uncertainty (:mod:`scenarios.scenes.perturb`: each parameter's u = U x its
        weight).  0: every sample is the nominal scene.
    seed : int
        The draws are a function of (seed, sample, parameter).
    distribution : {"uniform", "normal"}, optional
        Default: the perturb file's, else "uniform".
    perturb : path or dict, optional
        A ``--perturb`` TOML file, or the dict :func:`scenarios.scenes.perturb.load_perturb_file`
        returns.
    mode : str
        :func:`fmus.cosim.master.simulate`'s mode.
    out_dir : path, optional
        Where sweep.csv and the rest go (and where an earlier run of the same sweep is
        continued).  None: nothing written, everything computed.
    scheduler, workers, client, processes
        The cluster (:func:`scenarios.batch.engine.open_client`).
    stop_time : float, optional
        End every run early [s] (quick checks; windows not reached give NaN metrics).
    progress : callable, optional
        ``progress(fraction)`` of the missing samples done.
    on_row : callable, optional
        ``on_row(row)`` after each row is written.
    plots : bool
        Write sweep.png.

    Raises
    ------
    ValueError
        Bad N, U, seed, distribution or perturb file; an out_dir holding another sweep.
    """
    base = with_stop_time(get_scene(scene) if isinstance(scene, str) else scene, stop_time)
    if not (isinstance(samples, int) and samples >= 1):
        raise ValueError(f"samples = {samples!r} must be an integer >= 1")
    if not (isinstance(seed, int) and seed >= 0):
        raise ValueError(f"seed = {seed!r} must be an integer >= 0")
    spec = perturb if isinstance(perturb, dict) or perturb is None else load_perturb_file(perturb)
    spec = spec or {"uncertainty": {}, "distribution": None}
    distribution = distribution or spec.get("distribution") or "uniform"
    if distribution not in DISTRIBUTIONS:
        raise ValueError(f"distribution = {distribution!r}; valid: {', '.join(DISTRIBUTIONS)}")
    parameters = perturbable(base)
    spread = uncertainties(parameters, uncertainty, spec.get("uncertainty"))
    names = [p.name for p in parameters]
    settings = {"scene": base.name, "samples": samples, "uncertainty": float(uncertainty), "seed": seed,
                "distribution": distribution, "perturb": dict(spec.get("uncertainty") or {}), "mode": mode,
                "stop_time": base.system.stop_time, "parameters": names, "spread": spread}
    header = columns(names)
    done, files, appender = {}, [], None
    if out_dir is not None:
        out = check_writable(out_dir)
        settings_path, csv_path = out / "sweep.json", out / "sweep.csv"
        if settings_path.exists():
            _check_settings(settings_path, settings)
        if csv_path.exists():
            for row in read_rows(csv_path, header, repair=True):
                done.setdefault(row["sample"], row)
        files += [write_json(settings_path, settings), csv_path]
        appender = _Appender(csv_path, header)
    values = {i: draw(parameters, spread, seed, i, distribution) for i in range(samples) if i not in done}
    tasks = [Task(f"sample{i}", perturbed(base, parameters, v), mode) for i, v in values.items()]
    sample_of = {t.key: i for t, i in zip(tasks, values)}

    def record(task, metrics):
        i = sample_of[task.key]
        row = {"sample": i, **values[i], **{m: float(metrics[m]) for m in METRICS},
               "completed": bool(metrics["completed"]), **error_columns(metrics), "wall_s": float(metrics["wall_s"])}
        done[i] = row
        if appender is not None:
            appender.append(row)
        if on_row is not None:
            on_row(row)

    try:
        run_tasks(tasks, client=client, scheduler=scheduler, workers=workers, on_result=record, progress=progress,
                  processes=processes)
    finally:
        if appender is not None:
            appender.close()
    if out_dir is not None:       # the rows came in completion order; a reader wants them by sample
        ordered = "".join(_line(header, done[i]) for i in sorted(done))
        atomic_write(csv_path, lambda f: f.write(",".join(header) + "\n" + ordered))
    rows = [done[i] for i in range(samples)]
    sweep = Sweep(base.name, names, rows, summarize(rows), sorted(values), settings, files)
    if out_dir is not None:
        sweep.files.append(write_json(out / "summary.json", sweep.summary))
        sweep.files.append(atomic_write(out / "summary.md", lambda f: f.write(summary_markdown(sweep))))
        if plots:
            from scenarios.batch.sweep_plots import plot_sweep

            sweep.files.append(plot_sweep(sweep, out / "sweep.png"))
    return sweep
