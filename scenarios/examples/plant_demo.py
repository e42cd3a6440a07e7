"""Plant demo: the 5R of Table 3 driven open loop, with its workspace.

Run it with ``parcosim demo`` (or ``python -m scenarios.examples.plant_demo``).  It
starts the ``thesis_sim`` mechanism at rest at (0.07, 0.17) m (7.17), applies
smooth joint torques for 0.5 s, prints a short table and writes
``plant_demo.png``: the workspace map with its near-singular band (thesis
fig. 11) and the end-effector path.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from plant import PlantSimulator, get_preset
from plant.fivebar import workspace_map

DT = 1e-3


def torques(t: float) -> tuple[float, float]:
    """A smooth open-loop torque profile [N m]: τ1 = 0.03 sin(2π 2 t), τ2 = -0.03 sin(2π 3 t)."""
    return 0.03 * math.sin(2 * math.pi * 2 * t), -0.03 * math.sin(2 * math.pi * 3 * t)


def simulate(preset: str = "thesis_sim", x0: float = 0.07, y0: float = 0.17, t_end: float = 0.5):
    """Step the plant from rest; return rows (t, x, y, q1, q2, residual)."""
    sim = PlantSimulator(get_preset(preset), x0, y0)
    rows = []
    for k in range(round(t_end / DT) + 1):
        out = sim.outputs()
        rows.append((sim.time, out["x"], out["y"], out["q1"], out["q2"], out["residual"]))
        if k < round(t_end / DT):
            sim.step(*torques(sim.time), DT)
    return np.array(rows)


def plot(rows: np.ndarray, preset: str, path: Path) -> Path:
    """Workspace map, near-singular band and the simulated path."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    ws = workspace_map(get_preset(preset), step=0.002)
    fig, ax = plt.subplots(figsize=(6, 5))
    cmap = ListedColormap(["#1f3b73", "#a6c8ff", "#ffd34d"])
    ax.pcolormesh(ws.x, ws.y, ws.status, cmap=cmap, vmin=0, vmax=2, shading="nearest")
    ax.plot(rows[:, 1], rows[:, 2], color="red", lw=2, label="end-effector path")
    ax.plot(rows[0, 1], rows[0, 2], "wo", mec="k", label="start")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"5R workspace ({preset}); yellow: near-singular band")
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def run(out_dir: str | Path = "out", preset: str = "thesis_sim") -> Path:
    """Simulate, print a table every 50 ms and write the PNG; return its path."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    rows = simulate(preset)
    print(f"{'t [s]':>6} {'x [m]':>9} {'y [m]':>9} {'q1 [deg]':>9} {'q2 [deg]':>9} {'residual [m]':>12}")
    for t, x, y, q1, q2, res in rows[::50]:
        print(f"{t:6.3f} {x:9.5f} {y:9.5f} {math.degrees(q1):9.3f} {math.degrees(q2):9.3f} {res:12.2e}")
    path = plot(rows, preset, out_dir / "plant_demo.png")
    print(f"wrote {path}")
    return path


if __name__ == "__main__":
    run()
