"""scenarios/studies/workspace/spec.py's slice at the grid's edges (issue 31, session 44: boundaries
of the generalised training sample): on a small extent around the start, inside the bench 5R's
closed-form workspace everywhere, every grid point -- the first and last rows and columns
included -- is assembled."""
from __future__ import annotations

import numpy as np

from plant import fivebar, get_preset
from plant import spec as plant_spec
from scenarios.studies.workspace import spec as ws_spec


def test_a_slice_inside_the_workspace_assembles_its_first_and_last_rows_and_columns(monkeypatch):
    """Catches a grid index 0 (or the last) taken as outside the grid (``0 < i`` for ``0 <= i``)."""
    spec = plant_spec.load("bench_5r")
    x0, y0 = float(spec.start[0]), float(spec.start[1])
    extent = (x0 - 0.01, x0 + 0.01, y0 - 0.01, y0 + 0.01)
    closed = fivebar.workspace_map(get_preset("bench"), step=0.005, extent=extent)
    assert closed.x.size == 5 and np.all(closed.status != closed.OUTSIDE)
    monkeypatch.setattr(ws_spec, "SPEC_GRID", 5)
    ws, serial, parallel = ws_spec.slice_map(spec, 0.0, extent=extent)
    assert np.allclose(ws.x, closed.x, atol=1e-12) and np.allclose(ws.y, closed.y, atol=1e-12)
    assert np.all(ws.status == ws.INSIDE), ws.status
    assert not np.any(np.isnan(serial)) and not np.any(np.isnan(parallel))


def test_a_grid_point_whose_margin_is_exactly_the_band_is_inside_not_near_singular(monkeypatch):
    """The band as the controller takes it (margin < band is near-singular): with the band set to
    one grid point's own margin, that point is INSIDE and exactly the points of smaller margin
    are NEAR_SINGULAR.  Catches ``<=`` for ``<``."""
    spec = plant_spec.load("bench_5r")
    x0, y0 = float(spec.start[0]), float(spec.start[1])
    extent = (x0 - 0.01, x0 + 0.01, y0 - 0.01, y0 + 0.01)
    monkeypatch.setattr(ws_spec, "SPEC_GRID", 5)
    first, _, _ = ws_spec.slice_map(spec, 0.0, extent=extent)
    band = float(np.median(first.margin))
    ws, _, _ = ws_spec.slice_map(spec, band, extent=extent)
    at = ws.margin == band
    assert np.any(at) and np.all(ws.status[at] == ws.INSIDE)
    assert np.array_equal(ws.status == ws.NEAR_SINGULAR, ws.margin < band)
