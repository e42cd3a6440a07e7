"""The thesis' performance indices (7.31-7.32) of a scene's run.

``e_ef = sqrt(mean(e_x² + e_y²))`` and ``τ_ef = sqrt(mean(τ1² + τ2²))`` over the samples
of the scene's window (circle: steady state, t in [1, 8] s; triangle: the whole
trajectory); ``e_ss``: the RMS end-effector error over the last
:data:`scenarios.scenes.STEADY_STATE_WINDOW` s of the run, after the reference stopped.
"""
from __future__ import annotations

import math

import numpy as np

from .scenes import STEADY_STATE_WINDOW, Scene


def rms_norm(a: np.ndarray, b: np.ndarray) -> float:
    """sqrt(mean(a² + b²)); NaN for no samples."""
    return math.sqrt(float(np.mean(a * a + b * b))) if len(a) else float("nan")


def scene_metrics(scene: Scene, columns: dict, wall_s: float, completed: bool, init_s: float = 0.0) -> dict:
    """The contract's metrics (``e_ef_mm``, ``tau_ef_Nm``, ``e_ss_mm``, ``wall_s``,
    ``realtime_factor`` = simulated time / stepping wall time) and a few more (``init_s``:
loading and initialising the components, not in ``wall_s``), from result columns (name -> array, with ``t``).

    Windows that the run did not reach give NaN (written as null in JSON).
    """
    t = columns["t"]
    ex, ey = columns["x_d"] - columns["x"], columns["y_d"] - columns["y"]
    start, end = scene.window
    eps = 1e-9
    window = (t >= start - eps) & (t <= end + eps)
    reached_window = len(t) and t[-1] >= end - eps
    stop = scene.system.stop_time
    steady = t >= stop - STEADY_STATE_WINDOW - eps
    reached_stop = len(t) and t[-1] >= stop - eps
    simulated = float(t[-1]) if len(t) else 0.0
    extra = {}
    if "psi" in columns:   # the wheeled pendulum's scenes
        from .pendulum import pendulum_metrics

        extra = pendulum_metrics(columns, scene.system.step)
    return extra | {
        "scene": scene.name,
        "strategy": scene.strategy,
        "completed": bool(completed),
        "e_ef_mm": 1e3 * rms_norm(ex[window], ey[window]) if reached_window else float("nan"),
        "tau_ef_Nm": rms_norm(columns["tau1"][window], columns["tau2"][window]) if reached_window else float("nan"),
        "e_ss_mm": 1e3 * rms_norm(ex[steady], ey[steady]) if reached_stop and scene.reference_end < stop
        else float("nan"),
        "e_ss_x_mm": 1e3 * float(np.mean(ex[steady])) if reached_stop and scene.reference_end < stop
        else float("nan"),
        "e_ss_y_mm": 1e3 * float(np.mean(ey[steady])) if reached_stop and scene.reference_end < stop
        else float("nan"),
        "e_max_mm": 1e3 * float(np.max(np.hypot(ex, ey))) if len(t) else float("nan"),
        "window_s": [start, end],
        "simulated_s": simulated,
        "wall_s": wall_s,
        "init_s": init_s,
        "realtime_factor": simulated / wall_s if wall_s > 0 else float("nan"),
    }
