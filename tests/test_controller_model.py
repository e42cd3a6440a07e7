"""The tabulated model (7.2.5) against the exact one; model error scaling."""
import math

import numpy as np
import pytest

from controller.model import ExactModel, ModelRangeError, TabulatedModel, perturbed_params, tabulation_error
from plant import fivebar, get_preset

BENCH = get_preset("bench")
REGION = (-0.02, 0.02, 0.14, 0.18)


def test_table_reproduces_the_exact_model_at_grid_points():
    tab = TabulatedModel(BENCH, 0.01, REGION, cache=False)
    exact = ExactModel(BENCH)
    x, y = tab.xs[2], tab.ys[1]
    assert np.allclose(tab.terms(x, y, 0.4, -0.3), exact.terms(x, y, 0.4, -0.3), rtol=1e-10, atol=1e-14)


def test_interpolation_error_falls_like_h_squared():
    """Halving the grid step divides the error by about 4 (bilinear interpolation)."""
    errors = {}
    for step in (0.01, 0.005, 0.0025):
        errors[step] = tabulation_error(TabulatedModel(BENCH, step, REGION, cache=False), samples=40)
    for coarse, fine in ((0.01, 0.005), (0.005, 0.0025)):
        for term in ("H", "h"):
            ratio = errors[coarse][term] / errors[fine][term]
            assert 2.5 < ratio < 6.0, (term, coarse, errors)
    assert errors[0.005]["H"] < 1e-3


def test_left_out_points_raise_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    # A strip reaching the near-singular band near the x axis.
    tab = TabulatedModel(BENCH, 0.01, (-0.02, 0.02, 0.0, 0.06))
    assert (~tab.valid).any() and tab.valid.any()
    iy, ix = np.argwhere(~tab.cell_ok)[0]
    with pytest.raises(ModelRangeError, match="left out of the table"):
        tab.terms(tab.xs[ix] + 0.005, tab.ys[iy] + 0.005, 0.0, 0.0)
    with pytest.raises(ModelRangeError, match="outside the tabulated region"):
        tab.terms(0.0, 0.2, 0.0, 0.0)
    # The cache holds the table: a second instance loads it without building.
    again = TabulatedModel(BENCH, 0.01, (-0.02, 0.02, 0.0, 0.06))
    assert again.build_seconds == 0.0 and np.array_equal(again.table, tab.table, equal_nan=True)


def test_model_error_scales_inertia_and_quadratic_terms():
    e = 0.2
    a = ExactModel(BENCH).terms(0.0, 0.17, 0.3, 0.1)
    b = ExactModel(perturbed_params(BENCH, e)).terms(0.0, 0.17, 0.3, 0.1)
    assert np.allclose(b, np.array(a) * (1 + e), rtol=1e-12)
    with pytest.raises(ValueError, match="model_error = -1.5"):
        perturbed_params(BENCH, -1.5)


@pytest.mark.parametrize("step", [0.0, -0.005, float("nan"), float("inf")])
def test_grid_step_must_be_positive_and_finite(step):
    with pytest.raises(ValueError, match=r"grid step = .* m must be > 0"):
        TabulatedModel(BENCH, step, REGION, cache=False)


def test_table_is_cached_where_parcosim_cache_says(tmp_path, monkeypatch):
    """``$PARCOSIM_CACHE`` (docs/controller.md): the table is written there and read back."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    built = TabulatedModel(BENCH, 0.01, REGION)
    assert [p.suffix for p in tmp_path.iterdir()] == [".npz"] and built.build_seconds > 0.0
    loaded = TabulatedModel(BENCH, 0.01, REGION)
    assert loaded.build_seconds == 0.0 and np.array_equal(loaded.table, built.table, equal_nan=True)
