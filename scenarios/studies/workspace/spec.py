"""The workspace figure of :mod:`scenarios.studies.workspace.plot` for any mechanism spec: a slice.

The slice is the x-y plane through the platform's start point.  Each grid point is
assembled by Newton on the loop closure (5.18) from an already solved neighbour (a
flood fill from the start, so the working mode of the spec is kept); a point where
Newton fails, or jumps branch (a joint moves by more than :data:`MAX_JUMP` between
neighbours), is outside.  The singularity measures, each in [0, 1] and 0 when singular:

* serial (det J_Theta-like): the smallest over the largest singular value of A Q° (5.36,
  5.54), the constraints with the platform held: a chain stretched or folded;
* parallel (det J_X-like): the same for the columns of A that are not actuated, the
  constraints with the actuators held: the platform can move with the motors locked.
"""
from __future__ import annotations

import json
import math
from collections import deque

import numpy as np

from plant import fivebar
from plant import spec as plant_spec
from plant.parallel import left_inverse_solve, mechanism_state
from plant.specsim import assemble

from scenarios.studies.workspace.figure import (BAND, OUTSIDE, TrajectoryCheck, WorkspaceReport, draw,
                                                thesis_trajectories)

#: Largest joint change between neighbouring grid points on one branch [rad or m].
MAX_JUMP = 0.5
#: Grid lines per axis of a spec slice (each point costs a few Newton steps of the general model).
SPEC_GRID = 61


def measures(mech, q):
    """(serial, parallel) normalised singular-value measures at a closed configuration q."""
    st = mechanism_state(mech, q, np.zeros_like(q))
    free = [k for k in range(mech.n_coordinates) if k not in mech.actuated]
    out = []
    for cols in (st.A @ mech.Q_redundant, st.A[:, free]):
        cols = cols / np.linalg.norm(cols, axis=0)      # unit columns: lengths and angles alike
        s = np.linalg.svd(cols, compute_uv=False)
        out.append(float(s[-1] / s[0]))
    return out


def _solve(mech, q, iterations=12):
    Qo = mech.Q_redundant
    for _ in range(iterations):
        st = mechanism_state(mech, q, np.zeros_like(q))
        if np.linalg.norm(st.residual) < 1e-12:
            return q
        q = q - Qo @ left_inverse_solve(st.A @ Qo, st.residual)
        if not np.all(np.isfinite(q)):
            return None
    return q if np.linalg.norm(mechanism_state(mech, q, np.zeros_like(q)).residual) < 1e-10 else None


def slice_map(spec, band, extent=None):
    """A :class:`plant.fivebar.WorkspaceMap`-like grid of the slice, and both measures."""
    mech = spec.mechanism
    start = np.asarray(spec.start, dtype=float)
    if extent is None:   # around the start, as far as the longest chain reaches from its base
        reach = max(sum(abs(j.a) + abs(j.d) for j in c.chain.joints) + np.linalg.norm(c.base) for c in spec.chains)
        extent = (start[0] - reach, start[0] + reach, start[1] - reach, start[1] + reach)
    xs = np.linspace(extent[0], extent[1], SPEC_GRID)
    ys = np.linspace(extent[2], extent[3], SPEC_GRID)
    serial = np.full((ys.size, xs.size), np.nan)
    parallel = np.full_like(serial, np.nan)
    q0 = assemble(spec, start)
    i0 = (int(np.argmin(np.abs(ys - start[1]))), int(np.argmin(np.abs(xs - start[0]))))
    solved = {}
    queue = deque([(i0, q0)])
    while queue:
        (iy, ix), guess = queue.popleft()
        if (iy, ix) in solved or not (0 <= iy < ys.size and 0 <= ix < xs.size):
            continue
        q = guess.copy()
        q[0], q[1] = xs[ix], ys[iy]
        q = _solve(mech, q)
        if q is None or np.max(np.abs(q[3:] - guess[3:])) > MAX_JUMP:
            solved[(iy, ix)] = None
            continue
        solved[(iy, ix)] = q
        serial[iy, ix], parallel[iy, ix] = measures(mech, q)
        if min(serial[iy, ix], parallel[iy, ix]) < 1e-3:
            continue    # do not continue through a singularity: the branch would change
        for dy, dx in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            if (iy + dy, ix + dx) not in solved:
                queue.append(((iy + dy, ix + dx), q))
    margin = np.fmin(serial, parallel)
    status = np.where(np.isnan(margin), fivebar.WorkspaceMap.OUTSIDE,
                      np.where(margin < band, fivebar.WorkspaceMap.NEAR_SINGULAR, fivebar.WorkspaceMap.INSIDE))
    return fivebar.WorkspaceMap(xs, ys, margin, status), serial, parallel


def _check_on_grid(ws, name, reference, duration) -> TrajectoryCheck:
    ts = np.arange(int(round(duration / 1e-3)) + 1) * 1e-3
    pts = np.array([tuple(reference(t))[:2] for t in ts])
    check = TrajectoryCheck(name, pts[:, 0], pts[:, 1])
    ix = np.clip(np.rint((pts[:, 0] - ws.x[0]) / (ws.x[1] - ws.x[0])).astype(int), 0, ws.x.size - 1)
    iy = np.clip(np.rint((pts[:, 1] - ws.y[0]) / (ws.y[1] - ws.y[0])).astype(int), 0, ws.y.size - 1)
    status = ws.status[iy, ix]
    check.refused = {OUTSIDE: np.nonzero(status == ws.OUTSIDE)[0], BAND: np.nonzero(status == ws.NEAR_SINGULAR)[0]}
    margins = ws.margin[iy, ix]
    check.min_margin = float(np.nanmin(margins)) if np.any(~np.isnan(margins)) else math.nan
    return check


def plot_spec_slice(name, out, band) -> WorkspaceReport:
    """The figure and JSON of :func:`scenarios.studies.workspace.plot_workspace` for a spec."""
    spec = plant_spec.load(name)
    if not spec.is_parallel:
        raise ValueError(f"{spec.source}: a serial chain (no [platform]) has no parallel workspace to plot")
    ws, serial, parallel = slice_map(spec, band)
    checks = []
    if spec.independent == (0, 1) and len(spec.chains) == 2:     # a 5R: the thesis' references
        checks = [_check_on_grid(ws, n, ref, ref.duration)
                  for n, ref in {**thesis_trajectories("thesis_sim"), **thesis_trajectories("bench")}.items()]
    png = out / "workspace.png"
    where = "" if spec.independent == (0, 1) else f", slice z = {spec.start[2]:g} m"
    # The contours of the measures at a small level trace the loci (the measures are >= 0).
    level = 0.02
    draw(ws, np.where(np.isnan(parallel), np.nan, parallel - level), np.where(np.isnan(serial), np.nan, serial - level),
          checks, band, f"{spec.name}: workspace{where}", png,
          labels=(f"parallel measure = {level:g}", f"serial measure = {level:g}"))
    (out / "workspace.json").write_text(json.dumps(
        {"mechanism": spec.name, "band": band, "step": float(ws.x[1] - ws.x[0]),
         "points_inside": int(np.count_nonzero(ws.status != ws.OUTSIDE)),
         "trajectories": [c.summary() for c in checks]}, indent=2) + "\n")
    return WorkspaceReport(spec.name, png, band, checks)
