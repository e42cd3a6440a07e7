"""The PositionController's tabulated model refused before it is built when its grid would hold
more than MAX_TABLE_POINTS points (fmus/slaves/parcosim_positioncontroller.py ``_check_table``):
a grid of (x span / step + 1) columns times (y span / step + 1) rows, either span the long one.
Seed 4101's survivor [191] (the rows counted as y span * step) passed: no test made a grid too
large along y.  Steps and spans are powers of two so that every count is exact."""
from __future__ import annotations

import pytest

from fmus.slaves.parcosim_positioncontroller import MAX_TABLE_POINTS
from tests.fmus.slave.test_extremes import make_slave

STEP = 0.0625


@pytest.mark.parametrize("long_axis", ["x", "y"])
def test_a_grid_over_the_most_points_along_either_axis_is_refused_naming_its_points(long_axis, monkeypatch,
                                                                                      tmp_path):
    """3 points across the short axis (a span of two steps), 40001 along the long one (2500 m):
    120003 points, twice the most allowed, refused at initialisation with the count and every
    grid parameter named.  Catches either count computed otherwise (a product in place of the
    quotient makes 3 x 157 points, built instead)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))     # should a mutant build it: not the user's cache
    short, long = (-STEP, STEP), (0.0, 2500.0)
    (x_min, x_max), (y_min, y_max) = (long, short) if long_axis == "x" else (short, long)
    points = (2 + 1) * (2500.0 / STEP + 1)
    assert points == 120003 and points > MAX_TABLE_POINTS
    slave = make_slave("PositionController", {"strategy": "TCMDx", "cache": False, "grid_step": STEP, "x_min": x_min,
                                              "x_max": x_max, "y_min": y_min, "y_max": y_max})
    assert slave.error == (
        f"initialisation refused: parameters grid_step = {STEP!r}, x_min = {x_min!r}, x_max = {x_max!r}, "
        f"y_min = {y_min!r}, y_max = {y_max!r} m give a table of 1.2e+05 points, more than 60000 (building it would "
        "take initialisation over 10 s) (t = 0 s)")
