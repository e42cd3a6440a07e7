"""Run a scene and write what a user looks at: ``result.csv``, ``metrics.json``, plots.

``parcosim run SCENE [--mode fmu|inprocess|compiled] [--out DIR]`` is :func:`run_scene`::

    from scenarios.run.runner import run_scene
    outcome = run_scene("bench_circle_TCMDx", mode="inprocess", out_dir="out/tcmdx")
    print(outcome.metrics["e_ef_mm"])

A run that a component stops early, or that a KeyboardInterrupt (SIGINT) stops, still writes
the rows it recorded and metrics with ``"completed": false``, ``"outcome"`` its
:class:`fmus.status.RunStatus` and under ``"error"`` the record of why
(:meth:`fmus.status.RunError.record`: kind, message, instance, time, variable, value, unit,
code, reason; ``"interrupted": true`` for SIGINT).  Every file is written atomically (a temporary file in
the same directory, then ``os.replace``): a reader never sees half a file, and a failed
write (a full disk) leaves the previous file, if any, and raises :class:`WriteError` naming
the file.
"""
from __future__ import annotations

import errno
import json
import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fmus.export.archive import umask_mode
from fmus.cosim.master import Result, simulate

from scenarios.run.metrics import scene_metrics
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.scene import Scene


@dataclass
class Outcome:
    """A scene's run: the master's result, the named columns, the metrics, the files written."""

    scene: Scene
    result: Result
    columns: dict
    metrics: dict
    files: list


def result_columns(scene: Scene, result: Result) -> dict:
    """Column name -> array: ``t`` then the scene's columns."""
    columns = {"t": result.time}
    columns.update({name: result[signal] for name, signal in scene.columns.items()})
    return columns


def peak_rss_mb() -> float:
    """The process's peak resident set size so far [MB] (``getrusage`` ru_maxrss: the peak of the
    whole process since it started, not of one run; on Linux in KiB, on macOS in bytes)."""
    import resource
    import sys

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (1024.0 * 1024.0) if sys.platform == "darwin" else peak / 1024.0


def _json_safe(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value


class WriteError(OSError):
    """A result file could not be written; the message names the file."""


def atomic_write(path: Path, write) -> Path:
    """Call ``write(file)`` on a temporary text file beside ``path``, then rename it to
    ``path``.  On any OSError the temporary file is removed and :class:`WriteError`
    (naming ``path``) is raised; ``path`` keeps its previous content."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, umask_mode())       # mkstemp's 0600 -> what open() would give
        os.replace(tmp, path)
    except OSError as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        reason = exc.strerror or str(exc)
        raise WriteError(exc.errno or errno.EIO, f"cannot write {path}: {reason}") from None
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    return path


def check_writable(out_dir) -> Path:
    """Create ``out_dir`` if needed and check a file can be written in it (before a run);
    :class:`WriteError` naming the directory otherwise."""
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".parcosim-probe.", dir=out)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise WriteError(exc.errno or errno.EIO,
                         f"output directory {out} is not writable: {exc.strerror or exc}") from None
    return out


def write_csv(path: Path, columns: dict) -> Path:
    """One row per communication point, full double precision; written atomically."""
    data = np.column_stack(list(columns.values())) if len(columns["t"]) else np.empty((0, len(columns)))
    return atomic_write(path, lambda f: np.savetxt(f, data, delimiter=",", header=",".join(columns), comments="",
                                                   fmt="%.17g"))


def write_json(path: Path, value) -> Path:
    """``value`` as indented JSON (non-finite floats as null); written atomically."""
    text = json.dumps(_json_safe(value), indent=2) + "\n"
    return atomic_write(path, lambda f: f.write(text))


def plot_run(scene: Scene, columns: dict, out_dir: Path) -> list:
    """The thesis' figures: path against reference; e_x, e_y; tau1, tau2 (figures 12-23, 27-); a
    wheeled pendulum's scene (a ``psi`` column) has its own (:func:`scenarios.scenes.pendulum.plot_pendulum`)."""
    if "psi" in columns:
        from scenarios.scenes.pendulum import plot_pendulum

        return plot_pendulum(scene, columns, out_dir)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = columns["t"]
    files = []
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(1e3 * columns["x_d"], 1e3 * columns["y_d"], "k--", lw=1, label="reference")
    ax.plot(1e3 * columns["x"], 1e3 * columns["y"], "C0", lw=1, label="end effector")
    ax.set(xlabel="x [mm]", ylabel="y [mm]", title=scene.name, aspect="equal")
    ax.legend()
    files.append(out_dir / "path.png")
    fig.savefig(files[-1], dpi=120, bbox_inches="tight")
    plt.close(fig)
    for name, series, unit, scale in (
            ("errors.png", (("e_x", columns["x_d"] - columns["x"]), ("e_y", columns["y_d"] - columns["y"])), "mm", 1e3),
            ("torques.png", (("τ1", columns["tau1"]), ("τ2", columns["tau2"])), "N m", 1.0)):
        fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
        for ax, (label, values) in zip(axes, series):
            ax.plot(t, scale * values, lw=0.8)
            ax.set_ylabel(f"{label} [{unit}]")
            ax.grid(True, alpha=0.3)
            for edge in scene.window:
                ax.axvline(edge, color="0.6", lw=0.6, ls=":")
        axes[-1].set_xlabel("t [s]")
        axes[0].set_title(f"{scene.name} (dotted: metric window)")
        files.append(out_dir / name)
        fig.savefig(files[-1], dpi=120, bbox_inches="tight")
        plt.close(fig)
    return files


def run_scene(scene, mode: str = "inprocess", out_dir=None, coupling: str = "gauss-seidel",
              fmu_dir=None, plots: bool = True, progress=None, retry_substeps: int | None = None) -> Outcome:
    """Run a scene (a name or a :class:`Scene`) and, with ``out_dir``, write its files.

    ``retry_substeps`` (:func:`fmus.cosim.master.simulate`): a refused step is retried from the
    saved FMU states in that many sub-steps; ``metrics["retried_steps"]`` lists them as
    [time, instance].  ``mode="compiled"`` adds ``compile_s`` (generating and compiling the
    loop, or loading it from the cache; not in ``wall_s``) and ``python_steps`` (steps a
    kernel handed to the Python path), or ``fallback`` (why it ran in process instead);
    ``mode`` in the metrics is the mode that ran.  ``peak_rss_mb`` is the process's peak
    resident memory so far (:func:`peak_rss_mb`); ``cpu_s`` the CPU time of the stepping thread
    and ``realtime_factor_cpu`` = simulated time / ``cpu_s`` (on a machine shared with other
    jobs, steadier than the wall-time ``realtime_factor``).

    Returns the :class:`Outcome` also when a component stopped the run early
    (``outcome.result.error``); the files then hold what was recorded.
    """
    scene = get_scene(scene) if isinstance(scene, str) else scene
    if out_dir is not None:
        check_writable(out_dir)
    result = simulate(scene.system, mode=mode, coupling=coupling, fmu_dir=fmu_dir, progress=progress,
                      retry_substeps=retry_substeps)
    columns = result_columns(scene, result)
    metrics = scene_metrics(scene, columns, result.wall_s, result.completed, result.init_s)
    metrics.update({"mode": result.mode, "coupling": coupling, "order": list(result.order),
                    "peak_rss_mb": peak_rss_mb()})
    cpu = result.extra.get("cpu_s")
    if cpu:
        metrics["cpu_s"] = cpu
        metrics["realtime_factor_cpu"] = metrics["simulated_s"] / cpu
    if "compile_s" in result.extra:
        metrics["compile_s"] = result.extra["compile_s"]
        metrics["python_steps"] = result.extra["python_steps"]
    if "fallback" in result.extra:
        metrics["fallback"] = result.extra["fallback"]
    metrics["outcome"] = result.status.value
    if result.error is not None:
        metrics["error"] = result.error.record()
    if result.interrupted:
        metrics["interrupted"] = True
    if retry_substeps is not None:
        metrics["retried_steps"] = [[t, instance] for t, instance in result.extra.get("retried", [])]
    files = []
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        files.append(write_csv(out / "result.csv", columns))
        files.append(write_json(out / "metrics.json", metrics))
        if plots and len(columns["t"]) > 1 and not result.interrupted:
            files.extend(plot_run(scene, columns, out))
    return Outcome(scene, result, columns, metrics, files)


def error_message(metrics: dict) -> str:
    """The message of the ``error`` record in a run's ``metrics`` (:func:`run_scene`,
    :func:`scenarios.batch.engine.run_task`); "" when the run completed.  A metrics.json
    written before the record (its ``error`` the message itself) gives that text."""
    error = metrics.get("error") or {}
    return error if isinstance(error, str) else error.get("message", "")
