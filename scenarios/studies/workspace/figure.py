"""The workspace figure's parts: the refusal reasons, a trajectory's check against the controller
(:func:`check_trajectory`), the singularity measures and the drawing; :mod:`scenarios.studies.workspace.plot`
puts them together for a preset, :mod:`scenarios.studies.workspace.spec` for a spec."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from controller.model import DEFAULT_EXTENT
from controller.trajectories import circle, thesis_circle, triangle
from plant import fivebar

#: Refusal reasons of a reference sample, in the order the controller checks them.
OUTSIDE, BAND, TABLE = "outside the workspace", "in the near-singular band", "outside the controller's table"


@dataclass
class TrajectoryCheck:
    """One trajectory sampled every ``sample_time`` s: its path, and the samples the controller
    refuses."""

    name: str
    x: np.ndarray
    y: np.ndarray
    refused: dict = field(default_factory=dict)   # reason -> indices
    min_margin: float = math.inf
    sample_time: float = 1e-3

    def summary(self) -> dict:
        first = min((int(i[0]) for i in self.refused.values() if len(i)), default=None)
        margin = float(self.min_margin)     # inf (or nan) when no sample lies inside: JSON has no such number
        return {"name": self.name, "min_margin": margin if math.isfinite(margin) else None,
                "refused_samples": {r: int(len(i)) for r, i in self.refused.items() if len(i)},
                "first_refusal_s": None if first is None else first * self.sample_time}


@dataclass
class WorkspaceReport:
    """What :func:`scenarios.studies.workspace.plot.plot_workspace` drew and found."""

    mechanism: str
    png: Path
    band: float
    trajectories: list

    def summary(self) -> str:
        lines = [f"{self.mechanism}: {self.png}"]
        for t in self.trajectories:
            s = t.summary()
            verdict = ("accepted" if not s["refused_samples"] else
                       "REFUSED from t = {:.3f} s: {}".format(s["first_refusal_s"], ", ".join(
                           f"{n} samples {r}" for r, n in s["refused_samples"].items())))
            margin = "none (no sample inside)" if s["min_margin"] is None else f"{s['min_margin']:.3f}"
            lines.append(f"  {t.name}: min singularity margin {margin} (band {self.band:g}); {verdict}")
        return "\n".join(lines)


def thesis_trajectories(preset: str) -> dict:
    """The thesis' references for a preset: the simulation circle (7.18) for ``thesis_sim``,
    the bench circle (7.23) and triangle (7.24-7.27) for ``bench``."""
    if preset == "thesis_sim":
        return {"thesis_circle (7.18)": thesis_circle(cycles=1)}
    return {"circle (7.23)": circle(cycles=1), "triangle (7.24-7.27)": triangle(cycles=1)}


def user_circle(cx: float, cy: float, radius: float, period: float = 1.0):
    """A circle like (7.23) around (cx, cy), one turn in ``period`` [s]: a callable t -> (x, y)."""
    return lambda t: (cx + radius * math.sin(2 * math.pi * t / period), cy - radius * math.cos(2 * math.pi * t / period))


def check_trajectory(params, name, reference, duration, band=fivebar.NEAR_SINGULAR_MARGIN,
                     extent=DEFAULT_EXTENT, sample_time=1e-3) -> TrajectoryCheck:
    """Sample ``reference`` (t -> object with x, y, or a pair) every ``sample_time`` s (the
    controller's T, 1 ms) over ``duration`` and find the samples the controller refuses
    (controller.position: workspace, band, table)."""
    ts = np.arange(int(round(duration / sample_time)) + 1) * sample_time
    pts = np.array([tuple(reference(t))[:2] for t in ts])
    check = TrajectoryCheck(name, pts[:, 0], pts[:, 1], sample_time=sample_time)
    reasons = {OUTSIDE: [], BAND: [], TABLE: []}
    for i, (x, y) in enumerate(pts):
        try:
            margin = fivebar.singularity(params, x, y).margin
        except fivebar.KinematicsError:
            reasons[OUTSIDE].append(i)
            continue
        check.min_margin = min(check.min_margin, margin)
        if margin < band:
            reasons[BAND].append(i)
        elif not (extent[0] <= x <= extent[1] and extent[2] <= y <= extent[3]):
            reasons[TABLE].append(i)
    check.refused = {r: np.array(i, dtype=int) for r, i in reasons.items()}
    return check


def signed_measures(params, ws):
    """det J_X and det J_Theta on the grid of ``ws``, normalised by l2^2 and l1^2 l2^2 (seed 002
    eq. 16-17): det J_X = -l2^2 sin(phi12 - phi22), det J_Theta = l1^2 l2^2 sin(e1) sin(e2); NaN outside."""
    det_x = np.full(ws.margin.shape, np.nan)
    det_t = np.full(ws.margin.shape, np.nan)
    for iy, ix in zip(*np.nonzero(~np.isnan(ws.margin))):
        s = fivebar.singularity(params, ws.x[ix], ws.y[iy])
        det_x[iy, ix] = -s.parallel
        det_t[iy, ix] = s.serial1 * s.serial2
    return det_x, det_t


def draw(ws, det_x, det_t, checks, band, title, png, table=None, labels=("det J_X = 0", "det J_Θ = 0")):
    """The figure: workspace, band, both loci, the table's coverage, trajectories and refusals."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    fig, ax = plt.subplots(figsize=(10, 7))
    ax.pcolormesh(ws.x, ws.y, ws.status, cmap=ListedColormap(["#ffffff", "#cfe3ff", "#ffd34d"]),
                  vmin=0, vmax=2, shading="nearest")
    ax.contour(ws.x, ws.y, det_x, levels=[0.0], colors="#c0392b", linewidths=1.6)
    ax.contour(ws.x, ws.y, det_t, levels=[0.0], colors="#6c3483", linewidths=1.6, linestyles="--")
    inside = ~np.isnan(ws.margin)
    ax.contour(ws.x, ws.y, inside.astype(float), levels=[0.5], colors="#6c3483", linewidths=1.6, linestyles="--")
    handles = [Patch(color="#cfe3ff", label="workspace (working mode)"),
               Patch(color="#ffd34d", label=f"near-singular band (margin < {band:g}), refused"),
               Line2D([], [], color="#c0392b", lw=1.6, label=f"{labels[0]} (parallel)"),
               Line2D([], [], color="#6c3483", lw=1.6, ls="--", label=f"{labels[1]} (serial: the boundary)")]
    if table is not None:
        ax.add_patch(Rectangle((table[0], table[2]), table[1] - table[0], table[3] - table[2], fill=False,
                               ec="#1e8449", lw=1.4, ls=":"))
        handles.append(Line2D([], [], color="#1e8449", lw=1.4, ls=":", label="controller table (outside the band)"))
    colors = ["#1f618d", "#117864", "#7d3c98", "#935116", "#2c3e50"]
    marks = {OUTSIDE: "s", BAND: "x", TABLE: "^"}
    for c, color in zip(checks, colors):
        ax.plot(c.x, c.y, color=color, lw=1.8)
        handles.append(Line2D([], [], color=color, lw=1.8, label=c.name))
        for reason, idx in c.refused.items():
            if len(idx):
                ax.plot(c.x[idx], c.y[idx], marks[reason], color="#e74c3c", ms=3)
    for reason, mark in marks.items():
        if any(len(c.refused.get(reason, ())) for c in checks):
            handles.append(Line2D([], [], marker=mark, color="#e74c3c", ls="", label=f"refused: {reason}"))
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    fig.tight_layout()
    fig.savefig(png, dpi=120, bbox_inches="tight")     # the legend sits outside the axes
    plt.close(fig)
