"""plant.fivebar.workspace_map point by point: the grid spans the extent given, both ends
included, and each point's margin and status are those of the closed-form kinematics there
(plant.fivebar.singularity, inverse_kinematics) with the band given."""
import math

import numpy as np
import pytest

from plant import get_preset
from plant.fivebar import KinematicsError, WorkspaceMap, singularity, workspace_map


@pytest.mark.parametrize("preset, band", [("bench", 0.3), ("thesis_sim", 0.2)])
def test_every_grid_point_is_the_closed_form_at_that_point(preset, band):
    """Catches a grid that stops one step short of an end (x or y), a margin from another
    point or measure, and a band that is not the one given."""
    params = get_preset(preset)
    extent, step = (-0.12, 0.12, 0.0, 0.3), 0.03
    ws = workspace_map(params, step=step, band=band, extent=extent)
    np.testing.assert_allclose(ws.x, np.linspace(-0.12, 0.12, 9), rtol=0, atol=1e-12)
    np.testing.assert_allclose(ws.y, np.linspace(0.0, 0.3, 11), rtol=0, atol=1e-12)
    assert ws.margin.shape == ws.status.shape == (11, 9)
    statuses = set()
    for iy, y in enumerate(ws.y):
        for ix, x in enumerate(ws.x):
            try:
                margin = singularity(params, x, y).margin
            except KinematicsError:
                assert math.isnan(ws.margin[iy, ix]) and ws.status[iy, ix] == WorkspaceMap.OUTSIDE
                statuses.add(WorkspaceMap.OUTSIDE)
                continue
            assert ws.margin[iy, ix] == pytest.approx(margin, abs=1e-14), (x, y)
            expected = WorkspaceMap.NEAR_SINGULAR if margin < band else WorkspaceMap.INSIDE
            assert ws.status[iy, ix] == expected, (x, y)
            statuses.add(expected)
    assert statuses == {WorkspaceMap.OUTSIDE, WorkspaceMap.INSIDE, WorkspaceMap.NEAR_SINGULAR}


@pytest.mark.parametrize("extent, nx, ny", [((0.0, 0.026, 0.1, 0.123), 4, 3), ((0.0, 0.023, 0.1, 0.126), 3, 4)])
def test_a_grid_whose_extent_is_no_whole_number_of_steps_ends_at_the_point_nearest_each_end(extent, nx, ny):
    """Extents of 2.3 and 2.6 steps: the grid starts at the extent's start, steps by ``step``
    and ends at the grid point nearest the end (2 and 3 steps), so that no point of the extent
    is more than half a step from the grid.  Catches a grid end cut short by another margin
    than half a step, in x or in y."""
    step = 0.01
    ws = workspace_map(get_preset("bench"), step=step, extent=extent)
    np.testing.assert_allclose(ws.x, extent[0] + step * np.arange(nx), rtol=0, atol=1e-15)
    np.testing.assert_allclose(ws.y, extent[2] + step * np.arange(ny), rtol=0, atol=1e-15)
    for grid, start, end in ((ws.x, extent[0], extent[1]), (ws.y, extent[2], extent[3])):
        points = np.linspace(start, end, 101)
        assert np.max(np.min(np.abs(points[:, None] - grid[None, :]), axis=1)) <= step / 2


def test_a_point_whose_margin_is_exactly_the_band_is_inside_and_one_below_it_near_singular():
    """The band is "margin < band" (thesis fig. 11; :data:`plant.fivebar.NEAR_SINGULAR_MARGIN`): a
    band set to a grid point's own margin leaves that point INSIDE, and the next double above it
    makes it NEAR_SINGULAR.  Catches ``<=`` for ``<``."""
    params, extent, step = get_preset("bench"), (-0.12, 0.12, 0.0, 0.3), 0.03
    first = workspace_map(params, step=step, extent=extent)
    iy, ix = np.argwhere(first.status != WorkspaceMap.OUTSIDE)[0]
    band = float(first.margin[iy, ix])
    at = workspace_map(params, step=step, band=band, extent=extent)
    assert at.status[iy, ix] == WorkspaceMap.INSIDE
    above = workspace_map(params, step=step, band=float(np.nextafter(band, np.inf)), extent=extent)
    assert above.status[iy, ix] == WorkspaceMap.NEAR_SINGULAR
