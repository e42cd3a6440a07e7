"""The thesis' performance indices (7.31-7.32) of a scene's run, and the settled steady-state error.

``e_ef = sqrt(mean(e_x² + e_y²))`` and ``τ_ef = sqrt(mean(τ1² + τ2²))`` over the samples
of the scene's window (circle: steady state, t in [1, 8] s; triangle: the whole
trajectory).

``e_ss`` (the brief ../shared/spec/SYSTEM.md §5: "the end-effector error after the stop, once settled"; thesis
Tables 13-14) is the RMS error from the settling time to the end of the run
(:func:`settling`).  The end effector has **settled** at the first sample after the stop
from which it stays for good within :data:`SETTLE_BAND` of its final position (the mean
over the run's last :data:`STEADY_STATE_WINDOW` s), that is the classic settling time with
a band of one encoder count at the end effector; it counts as settled only if it stays
there at least :data:`SETTLE_HOLD` s before the run ends.  Why one count: the controller
reads 20000-count encoders, so a motion below one count is one it cannot see or correct; a
band any narrower would call the encoder's own dither (a limit cycle between two counts)
unsettled, a band much wider would call a slow creep settled.  When the run ends before
the end effector settles, ``settled`` is false, ``t_settle_s`` null, and ``e_ss_mm`` is
the RMS over the last :data:`STEADY_STATE_WINDOW` s (the best the run can say).

``e_contour_sides_mm`` (polygon references: the triangle's scenes) is, per side in travel
order, the RMS distance of the end effector from the polygon's path while the reference
travels that side (:func:`side_contour_errors`): where the error lies, as an xy plot shows it.

``e_ss_1s_mm`` keeps the earlier definition: the RMS over
[stop + :data:`E_SS_1S` − :data:`STEADY_STATE_WINDOW`, stop + :data:`E_SS_1S`], 1 s after
the reference stopped, whether settled or not.
"""
from __future__ import annotations

import math

import numpy as np

from controller.trajectories import PolygonTrajectory, from_parameters

from scenarios.scenes.scene import STEADY_STATE_WINDOW, Scene

#: Settling band [m]: one encoder count (2π/20000 rad) of either base joint moves the end
#: effector by 0.0498-0.0504 mm at the hold points of the circle (0, 0.108) and of the
#: triangle (-0.002, 0.108) with the bench's geometry (Tables 4-5): 0.05 mm.
SETTLE_BAND = 5.0e-5
#: The end effector must stay in the band at least this long before the run ends to count
#: as settled [s]: ten times the slowest closed-loop time constant of Tables 6-8
#: (1/λ with λ = 20 rad/s: 50 ms), so a creep slower than the band per 0.5 s shows.
SETTLE_HOLD = 0.5
#: The earlier steady-state error was measured this long after the stop [s] (``e_ss_1s_mm``).
E_SS_1S = 1.0
#: Slack on every window edge [s]: a sample time's rounding (k h is not k times h exactly).
SLACK = 1e-9


def rms_norm(a: np.ndarray, b: np.ndarray) -> float:
    """sqrt(mean(a² + b²)); NaN for no samples."""
    return math.sqrt(float(np.mean(a * a + b * b))) if len(a) else float("nan")


def side_contour_errors(polygon: PolygonTrajectory, t, x, y) -> list:
    """Per side of ``polygon``, in travel order, the RMS distance [m] of the end effector (x, y)
    from the polygon's path over the samples while the reference travels that side.

    A sample at t belongs to side k mod n when t is in [k T, (k + 1) T) (T the side time, n the
    sides, k below cycles × n); its distance is to the nearest point of the closed path.  The
    distance to the path, not to the reference point: the error an xy tracking plot shows, blind
    to a lag along the path (the thesis says where its triangle's error lies from such plots,
    7.2.12).  NaN for a side with no sample (a run that stopped early).
    """
    t, x, y = (np.asarray(a, dtype=float) for a in (t, x, y))
    vertices = np.asarray(polygon.vertices, dtype=float)
    n = len(vertices)
    distance = np.full(len(t), np.inf)
    for a, b in zip(vertices, np.roll(vertices, -1, axis=0)):
        ab = b - a
        along = np.clip(((x - a[0]) * ab[0] + (y - a[1]) * ab[1]) / (ab @ ab), 0.0, 1.0)
        distance = np.minimum(distance, np.hypot(x - a[0] - along * ab[0], y - a[1] - along * ab[1]))
    index = np.floor(t / polygon.side_time)
    travelling = (t >= 0.0) & (index < polygon.cycles * n)
    side = index.astype(int) % n
    return [math.sqrt(float(np.mean(distance[travelling & (side == k)] ** 2)))
            if np.any(travelling & (side == k)) else float("nan") for k in range(n)]


def scene_polygon(scene: Scene) -> PolygonTrajectory | None:
    """The polygon the scene's ``Trajectory`` component follows, or None (another kind, or no
    such component)."""
    for c in scene.system.components:
        if c.model == "Trajectory":
            trajectory = from_parameters(**c.parameters)
            return trajectory if isinstance(trajectory, PolygonTrajectory) else None
    return None


def settling(t: np.ndarray, ex: np.ndarray, ey: np.ndarray, stop: float, band: float = SETTLE_BAND,
             hold: float = SETTLE_HOLD, final_window: float = STEADY_STATE_WINDOW) -> tuple:
    """When the end-effector error ``(ex, ey)`` settled after the reference stopped at ``stop``.

    Parameters
    ----------
    t, ex, ey : arrays
        Sample times [s] and error components [m] (x_d - x, y_d - y) of the whole run.
    stop : float
        When the reference stopped [s].
    band, hold, final_window : float
        Settling band [m], least time in it before the run's end [s], the final-position
        window [s] (module docstring).

    Returns
    -------
    (settled, t_settle, mask)
        ``settled`` (bool); ``t_settle`` the time since the reference stopped [s] (NaN if not
        settled); ``mask`` the samples e_ss is taken over (from the settling time on, or the
        last ``final_window`` s when the run did not settle).
    """
    eps = SLACK
    last = t >= t[-1] - final_window - eps
    after = t >= stop - eps
    fx, fy = float(np.mean(ex[last])), float(np.mean(ey[last]))
    outside = after & (np.hypot(ex - fx, ey - fy) > band)
    if outside.any():
        k = int(np.flatnonzero(outside)[-1]) + 1    # the first sample after the last one outside
    else:
        k = int(np.flatnonzero(after)[0])
    if k >= len(t) or t[-1] - t[k] < hold - eps:
        return False, float("nan"), last
    return True, float(t[k] - stop), t >= t[k] - eps


def _steady_state(t, ex, ey, scene: Scene) -> dict:
    stop = scene.reference_end
    eps = SLACK
    none = {"e_ss_mm": float("nan"), "e_ss_x_mm": float("nan"), "e_ss_y_mm": float("nan"),
            "settled": False, "t_settle_s": float("nan"), "e_ss_1s_mm": float("nan")}
    end = scene.system.stop_time
    if not (len(t) and t[-1] >= end - eps and stop < end):
        return none
    settled, t_settle, mask = settling(t, ex, ey, stop)
    at_1s = (t >= stop + E_SS_1S - STEADY_STATE_WINDOW - eps) & (t <= stop + E_SS_1S + eps)
    return {"e_ss_mm": 1e3 * rms_norm(ex[mask], ey[mask]),
            "e_ss_x_mm": 1e3 * float(np.mean(ex[mask])), "e_ss_y_mm": 1e3 * float(np.mean(ey[mask])),
            "settled": settled, "t_settle_s": t_settle,
            "e_ss_1s_mm": 1e3 * rms_norm(ex[at_1s], ey[at_1s]) if end >= stop + E_SS_1S - eps else float("nan")}


def in_window(t: np.ndarray, window: tuple) -> np.ndarray:
    """The samples of times ``t`` in the metric window ``(start, end)``, both ends included with
    :data:`SLACK` (a nanosecond) for a sample time's rounding: ``start - SLACK <= t <= end + SLACK``.
    e_ef, tau_ef and every study's peaks and RMS values are taken over the same samples."""
    start, end = window
    return (t >= start - SLACK) & (t <= end + SLACK)


def scene_metrics(scene: Scene, columns: dict, wall_s: float, completed: bool, init_s: float = 0.0) -> dict:
    """The contract's metrics (``e_ef_mm``, ``tau_ef_Nm``, ``e_ss_mm``, ``wall_s``,
    ``realtime_factor`` = simulated time / stepping wall time) and a few more (``init_s``:
    loading and initialising the components, not in ``wall_s``; ``settled``, ``t_settle_s``,
    ``e_ss_1s_mm``: module docstring), from result columns (name -> array, with ``t``).

    Windows that the run did not reach give NaN (written as null in JSON).
    """
    t = columns["t"]
    ex, ey = columns["x_d"] - columns["x"], columns["y_d"] - columns["y"]
    start, end = scene.window
    eps = SLACK
    window = in_window(t, scene.window)
    reached_window = len(t) and t[-1] >= end - eps
    simulated = float(t[-1]) if len(t) else 0.0
    extra = {}
    if "psi" in columns:   # the wheeled pendulum's scenes
        from scenarios.scenes.pendulum import pendulum_metrics

        extra = pendulum_metrics(columns, scene.system.step)
    polygon = scene_polygon(scene)
    if polygon is not None:
        extra["e_contour_sides_mm"] = [1e3 * e for e in side_contour_errors(polygon, t, columns["x"], columns["y"])]
    return extra | {
        "scene": scene.name,
        "strategy": scene.strategy,
        "completed": bool(completed),
        "e_ef_mm": 1e3 * rms_norm(ex[window], ey[window]) if reached_window else float("nan"),
        "tau_ef_Nm": rms_norm(columns["tau1"][window], columns["tau2"][window]) if reached_window else float("nan"),
        **_steady_state(t, ex, ey, scene),
        "e_max_mm": 1e3 * float(np.max(np.hypot(ex, ey))) if len(t) else float("nan"),
        "window_s": [start, end],
        "simulated_s": simulated,
        "wall_s": wall_s,
        "init_s": init_s,
        "realtime_factor": simulated / wall_s if wall_s > 0 else float("nan"),
    }
