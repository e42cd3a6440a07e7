"""controller/model.py's TabulatedModel refuses a grid with fewer than 2 lines along an axis
(a step larger than the extent): such a table has no cell to interpolate in, and was cached,
then refused as unreadable on every later load (session 43, s2's finding)."""
from __future__ import annotations

import pytest

from controller.model import TabulatedModel
from plant import get_preset

PARAMS = get_preset("bench")


@pytest.mark.parametrize("step, extent, nx, ny", [(0.5, (-0.1, 0.1, 0.05, 0.25), 1, 1),
                                                   (0.15, (-0.1, 0.1, 0.05, 0.1), 2, 1),
                                                   (0.15, (-0.05, 0.02, 0.05, 0.25), 1, 2)])
def test_a_grid_without_two_lines_along_each_axis_is_refused_and_nothing_is_cached(tmp_path, monkeypatch, step,
                                                                                   extent, nx, ny):
    """Catches the check dropped (the 1-line table built and cached), made on one axis only, or
    counted otherwise than the grid the table is built on."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    with pytest.raises(ValueError) as refused:
        TabulatedModel(PARAMS, step, extent)
    assert str(refused.value) == (f"grid step = {step!r} m over extent = {extent!r} gives {nx} x {ny} grid points: "
                                  "the table interpolates in cells of 2 x 2 points")
    assert list(tmp_path.iterdir()) == []


def test_a_grid_of_two_lines_along_each_axis_is_built():
    """The smallest table accepted: 2 x 2 points, one cell."""
    model = TabulatedModel(PARAMS, 0.1, (-0.05, 0.05, 0.1, 0.2), cache=False)
    assert (model.xs.size, model.ys.size) == (2, 2)
