"""Where the 5R can go, and why the controller refuses a trajectory (seed 002, thesis fig. 11).

``parcosim workspace [PRESET or SPEC.toml] [--out DIR]`` calls :func:`plot_workspace`:
``DIR/workspace.png`` and ``DIR/workspace.json``.  For a preset (``thesis_sim``, ``bench``)
the figure shows, in the working mode (elbows outward):

* the reachable workspace (:func:`plant.fivebar.workspace_map`);
* both singularity loci of seed 002: det J_Theta = 0 (eq. 17: a chain stretched or
  folded; in the working mode this is the workspace's boundary) and det J_X = 0 (eq. 16:
  the distal links aligned), drawn as the zero contours of the signed measures of
  :func:`plant.fivebar.singularity`;
* the near-singular band the controller refuses (margin < ``band``, by default
  :data:`plant.fivebar.NEAR_SINGULAR_MARGIN`, the controller's default);
* the controller table's coverage (:data:`controller.model.DEFAULT_EXTENT`, 5 mm grid;
  the points it tabulates are those outside the band, 7.2.5);
* the thesis' trajectories (7.18, 7.23, 7.24-7.27) and any extra circle, each sample the
  controller would refuse marked with its reason (outside the workspace, in the band,
  outside the table).

For a spec (:mod:`plant.spec`), the same plot on a slice through the platform's start
point (the x-y plane at the start's z): points are assembled by Newton from a solved
neighbour (a flood fill from the start, so the working mode is kept), and the two
measures are the normalised smallest singular values of the constraint Jacobian
(5.36) with the platform held (A Q°: the serial, det J_Theta-like singularity) and with
the actuators held (the parallel, det J_X-like one).
"""
from __future__ import annotations

import json
from pathlib import Path

from controller.model import DEFAULT_EXTENT, DEFAULT_GRID_STEP
from plant import PRESET_NAMES, fivebar, get_preset
from scenarios.studies.workspace.figure import (WorkspaceReport, draw, check_trajectory, signed_measures,
                                                thesis_trajectories, user_circle)
from scenarios.studies.workspace.spec import plot_spec_slice


def plot_workspace(mechanism="bench", out_dir="out/workspace", band=fivebar.NEAR_SINGULAR_MARGIN,
                   step=0.002, circles=()) -> WorkspaceReport:
    """Draw the workspace figure of a preset or a spec; write ``workspace.png`` and
    ``workspace.json`` in ``out_dir``.

    Parameters
    ----------
    mechanism : str
        A preset name (``thesis_sim``, ``bench``) or a spec (path or shipped name, :mod:`plant.spec`).
    band : float
        Width of the near-singular band (singularity margin), the controller's ``band``.
    step : float
        Grid step of the map [m] (a preset's; a spec's slice has ``SPEC_GRID`` lines per axis).
    circles : sequence of (cx, cy, r)
        Extra 1 Hz circles to check, as (7.23) [m].
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if mechanism not in PRESET_NAMES:
        return plot_spec_slice(mechanism, out, band)
    params = get_preset(mechanism)
    refs = {name: (traj, traj.duration) for name, traj in thesis_trajectories(mechanism).items()}
    for cx, cy, r in circles:
        refs[f"circle ({cx:g}, {cy:g}) r {r:g}"] = (user_circle(cx, cy, r), 1.0)
    checks = [check_trajectory(params, name, ref, duration, band) for name, (ref, duration) in refs.items()]
    ws = fivebar.workspace_map(params, step=step, band=band)     # the whole reach: every branch, below the bases too
    det_x, det_t = signed_measures(params, ws)
    png = out / "workspace.png"
    draw(ws, det_x, det_t, checks, band, f"5R workspace, preset {mechanism} (elbows outward)", png,
          table=DEFAULT_EXTENT)
    report = WorkspaceReport(mechanism, png, band, checks)
    (out / "workspace.json").write_text(json.dumps(
        {"mechanism": mechanism, "band": band, "map_extent": [ws.x[0], ws.x[-1], ws.y[0], ws.y[-1]],
         "table_extent": DEFAULT_EXTENT, "table_step": DEFAULT_GRID_STEP,
         "trajectories": [c.summary() for c in checks]}, indent=2) + "\n")
    return report
