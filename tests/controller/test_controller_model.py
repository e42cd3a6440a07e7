"""The tabulated model (7.2.5) against the exact one; model error scaling."""
import math
import re
import time
import warnings

import numpy as np
import pytest

from controller.model import (ExactModel, ModelRangeError, TabulatedModel, cache_dir, perturbed_params,
                              tabulation_error)
from plant import fivebar, get_preset

BENCH = get_preset("bench")
REGION = (-0.02, 0.02, 0.14, 0.18)


def test_table_reproduces_the_exact_model_at_grid_points():
    """Catches a tabulated model that is off the exact model at its own grid points (an index swap)."""
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
    """Catches a table that interpolates across left-out or outside cells instead of refusing."""
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
    """Catches a model error that does not scale all terms by (1 + e), or accepts e <= -1."""
    e = 0.2
    a = ExactModel(BENCH).terms(0.0, 0.17, 0.3, 0.1)
    b = ExactModel(perturbed_params(BENCH, e)).terms(0.0, 0.17, 0.3, 0.1)
    assert np.allclose(b, np.array(a) * (1 + e), rtol=1e-12)
    with pytest.raises(ValueError, match="model_error = -1.5"):
        perturbed_params(BENCH, -1.5)


@pytest.mark.parametrize("step", [0.0, -0.005, float("nan"), float("inf")])
def test_grid_step_must_be_positive_and_finite(step):
    """Catches a table built with a zero, negative, NaN or infinite grid step."""
    with pytest.raises(ValueError, match=r"grid step = .* m must be > 0"):
        TabulatedModel(BENCH, step, REGION, cache=False)


def test_table_is_cached_where_parcosim_cache_says(tmp_path, monkeypatch):
    """``$PARCOSIM_CACHE`` (docs/controller.md): the table is written there and read back."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    built = TabulatedModel(BENCH, 0.01, REGION)
    assert [p.suffix for p in tmp_path.iterdir()] == [".npz"] and built.build_seconds > 0.0
    loaded = TabulatedModel(BENCH, 0.01, REGION)
    assert loaded.build_seconds == 0.0 and np.array_equal(loaded.table, built.table, equal_nan=True)


def test_a_table_cached_by_other_kernels_is_built_again(tmp_path, monkeypatch):
    """The table is the C exact model's output: a table cached by another build of the kernels
    (``kernels.code_version``, the library's hash of its sources and flags) is not read back but
    built again.  Wrong code it catches: a cache key without the code version, which served a
    table from before a kernel change (found when the native controller, building its own
    table, differed by an ulp from the pythonfmu one reading a stale cache)."""
    import kernels

    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    TabulatedModel(BENCH, 0.01, REGION)
    monkeypatch.setattr(kernels, "code_version", lambda: "another build")
    again = TabulatedModel(BENCH, 0.01, REGION)
    assert again.build_seconds > 0.0 and len(list(tmp_path.iterdir())) == 2


def test_near_singular_grid_points_are_left_out(tmp_path, monkeypatch):
    """Near a singularity H and h grow without bound (det J -> 0): a grid point whose margin
    (plant.fivebar.singularity, sines of the elbow and distal-link angles) is below the band
    must not enter the table; every other point of the workspace must."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    tab = TabulatedModel(BENCH, 0.01, (-0.02, 0.02, 0.0, 0.06))
    band = fivebar.NEAR_SINGULAR_MARGIN
    near = 0
    for iy, y in enumerate(tab.ys):
        for ix, x in enumerate(tab.xs):
            try:
                margin = fivebar.singularity(BENCH, x, y).margin
            except fivebar.KinematicsError:
                assert not tab.valid[iy, ix]
                continue
            assert tab.valid[iy, ix] == (margin >= band), (x, y, margin)
            near += margin < band
    assert near > 0


@pytest.mark.parametrize("dx, dy", [(1e-6, 0.0), (0.025, 0.0), (0.0, 1e-6), (0.0, 0.025)])
def test_points_beyond_the_far_edges_are_outside(dx, dy, tmp_path, monkeypatch):
    """Catches an off-by-one at the table's far edges: points just beyond them must be outside."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    tab = TabulatedModel(BENCH, 0.01, REGION)
    x = (REGION[1] + dx) if dx else 0.0
    y = (REGION[3] + dy) if dy else 0.16
    with pytest.raises(ModelRangeError, match="outside the tabulated region"):
        tab.terms(x, y, 0.0, 0.0)


def test_build_time_is_a_wall_time(tmp_path, monkeypatch):
    """Catches a build time that is not measured, or not in seconds of wall time."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    start = time.perf_counter()
    tab = TabulatedModel(BENCH, 0.01, REGION)
    assert 0.0 < tab.build_seconds <= time.perf_counter() - start


def test_default_cache_dir_is_under_the_home_cache(tmp_path, monkeypatch):
    """cache_dir (docs/controller.md): $PARCOSIM_CACHE, else $XDG_CACHE_HOME/parcosim, else ~/.cache/parcosim."""
    monkeypatch.delenv("PARCOSIM_CACHE", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))
    assert cache_dir() == tmp_path / ".cache" / "parcosim"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "xdg" / "parcosim"


@pytest.mark.parametrize("kernel", ["fast", "general"])
def test_velocity_terms_are_passive(kernel):
    """With no gravity (the bench is horizontal) the kinetic energy T = ½ ẋᵀ H ẋ changes only
    by the power of the efforts, so ẋᵀ h(x, ẋ) = ½ ẋᵀ Ḣ ẋ (the skew symmetry of Ḣ - 2C).
    Ḣ by central differences of H along ẋ; checked at random poses and velocities."""
    model = ExactModel(BENCH, kernel=kernel)
    rng = np.random.default_rng(18)
    checked = 0
    while checked < 8:
        x, y = rng.uniform(-0.04, 0.04), rng.uniform(0.12, 0.2)
        if model.kin.margin(x, y) < 0.2:
            continue
        v = rng.normal(0.0, 0.3, 2)
        H00, H01, H11, h0, h1 = model.terms(x, y, *v)
        delta = 1e-6

        def H(s):
            a, b, c, _, _ = model.terms(x + s * v[0], y + s * v[1], 0.0, 0.0)
            return np.array([[a, b], [b, c]])

        dH = (H(delta) - H(-delta)) / (2 * delta)
        assert v @ np.array([h0, h1]) == pytest.approx(0.5 * v @ dH @ v, rel=1e-6, abs=1e-12)
        checked += 1


def test_tabulation_error_checks_h_in_directions_all_around(monkeypatch):
    """ĥ's velocity part is a quadratic form in (dx, dy): its table error depends on the
    direction, so :func:`tabulation_error` draws |v| = 1 m/s in a direction uniform on the
    circle (its docstring), not from one sector where the error could be smaller."""
    seen = []
    exact_terms = ExactModel.terms

    def recording(self, x, y, dx, dy):
        seen.append((dx, dy))
        return exact_terms(self, x, y, dx, dy)

    monkeypatch.setattr(ExactModel, "terms", recording)
    tabulation_error(TabulatedModel(BENCH, 0.01, REGION, cache=False), samples=40)
    v = np.array(seen)
    assert len(v) == 40 and np.allclose(np.hypot(v[:, 0], v[:, 1]), 1.0, rtol=1e-12)
    quadrants = {(bool(dx > 0), bool(dy > 0)) for dx, dy in v}
    assert len(quadrants) == 4


def test_the_complete_cells_are_those_the_kernel_interpolates(tmp_path, monkeypatch):
    """``cell_ok`` (the cells tabulation_error samples) against the law kernel's own hole check:
    a cell is complete exactly when a point inside it interpolates, for every cell of a table
    with holes.  Catches a shifted or mirrored corner in ``cell_ok`` (an index -1 for 1)."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    tab = TabulatedModel(BENCH, 0.01, (-0.02, 0.03, 0.0, 0.06))
    assert tab.cell_ok.shape == (tab.ys.size - 1, tab.xs.size - 1)
    assert tab.cell_ok.any() and not tab.cell_ok.all()
    for iy, ix in np.ndindex(tab.cell_ok.shape):
        for fx, fy in ((0.25, 0.5), (0.75, 0.25)):
            x, y = tab.xs[ix] + fx * tab.step, tab.ys[iy] + fy * tab.step
            try:
                tab.interpolate(x, y)
                interpolates = True
            except ModelRangeError:
                interpolates = False
            assert interpolates == tab.cell_ok[iy, ix], (iy, ix, x, y)


def test_the_default_table_is_the_documented_grid(tmp_path, monkeypatch):
    """docs/controller.md: default step 5 mm, region x in [-0.12, 0.12], y in [0.06, 0.29] m
    (written here, not read from the module).  The table built without arguments, and the one
    a default PositionController holds, span it to rounding with 49 x 47 points.  Catches a
    default extent or step that is not the documented one (a sign lost, an end moved): the
    controller would then fall back to the exact model, or refuse, on part of the thesis' region."""
    from controller.position import PositionController
    from controller.strategies import get_strategy

    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    for tab in (TabulatedModel(BENCH), PositionController(BENCH, get_strategy("TCx")).model):
        assert isinstance(tab, TabulatedModel)
        np.testing.assert_allclose([tab.xs[0], tab.xs[-1], tab.ys[0], tab.ys[-1]], [-0.12, 0.12, 0.06, 0.29],
                                   rtol=0, atol=1e-12)
        assert (len(tab.xs), len(tab.ys)) == (49, 47)
        np.testing.assert_allclose(np.diff(tab.xs), 0.005, rtol=0, atol=1e-12)
        np.testing.assert_allclose(np.diff(tab.ys), 0.005, rtol=0, atol=1e-12)


@pytest.mark.parametrize("region", [(-0.005, 0.005, 0.14, 0.18), (-0.02, 0.02, 0.155, 0.165),
                                    (-0.005, 0.005, 0.155, 0.165)], ids=["2 xs", "2 ys", "2 by 2"])
def test_a_cached_table_of_two_points_a_side_is_read_back_without_a_warning(region, tmp_path, monkeypatch):
    """Two grid points a side make one cell, the smallest table there is: it is a table, read
    back from the cache as it was written (not refused as unreadable and built again)."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    built = TabulatedModel(BENCH, 0.01, region)
    assert 2 in built.table.shape[:2]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        loaded = TabulatedModel(BENCH, 0.01, region)
    assert loaded.build_seconds == 0.0 and np.array_equal(loaded.table, built.table, equal_nan=True)


@pytest.mark.parametrize("extent", [(0.01, 0.01, 0.14, 0.18), (0.02, -0.02, 0.14, 0.18),
                                    (-0.02, 0.02, 0.16, 0.16), (-0.02, 0.02, 0.18, 0.14)],
                         ids=["x flat", "x reversed", "y flat", "y reversed"])
def test_an_extent_empty_along_either_axis_alone_is_refused_naming_it(extent, tmp_path, monkeypatch):
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    with pytest.raises(ValueError, match=rf"^extent = {re.escape(repr(extent))} is empty$"):
        TabulatedModel(BENCH, 0.01, extent)
    assert not list(tmp_path.iterdir())


def _bad_caches(xs, ys, table):
    """Cache files that are not a table of the model, each for one clause of the check."""
    return {
        "not an npz": None,
        "xs 2-d": dict(xs=xs[None, :], ys=ys, table=table),
        "ys 2-d": dict(xs=xs, ys=ys[None, :], table=table),
        "table transposed": dict(xs=xs, ys=ys, table=table.transpose(1, 0, 2)),
        "one x": dict(xs=xs[:1], ys=ys, table=table[:, :1]),
        "one y": dict(xs=xs, ys=ys[:1], table=table[:1]),
        "no table": dict(xs=xs, ys=ys),
    }


@pytest.mark.parametrize("case", list(_bad_caches(np.zeros(3), np.zeros(3), np.zeros((3, 3, 11)))))
def test_a_cache_file_that_is_not_a_table_is_rebuilt_with_a_warning_naming_it(case, tmp_path, monkeypatch):
    """Each way a cache file can fail to be a table (unreadable, a wrong rank, shapes that do
    not fit, fewer than two points a side, an array missing) is warned about, naming the file,
    and the table is built again: the same as the first build."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    region = (-0.02, 0.02, 0.15, 0.18)     # 4 ys, 5 xs: a transposed table does not fit
    built = TabulatedModel(BENCH, 0.01, region)
    assert built.table.shape[:2] == (4, 5)
    (path,) = tmp_path.iterdir()
    xs = np.asarray(region[0] + 0.01 * np.arange(built.table.shape[1]))
    ys = np.asarray(region[2] + 0.01 * np.arange(built.table.shape[0]))
    arrays = _bad_caches(xs, ys, built.table)[case]
    if arrays is None:
        path.write_bytes(b"not a table")
    else:
        with open(path, "wb") as f:
            np.savez(f, **arrays)
    with pytest.warns(UserWarning, match=rf"controller table cache {re.escape(str(path))} is unreadable .*"
                                         "rebuilding the table"):
        again = TabulatedModel(BENCH, 0.01, region)
    assert again.build_seconds > 0.0 and np.array_equal(again.table, built.table, equal_nan=True)


@pytest.mark.parametrize("kernel", ["fast", "general"])
def test_the_exact_models_terms_and_its_table_row_give_the_same_inertia_exactly(kernel):
    """terms() and row() of one ExactModel read H = (H00, H01, H11) off the same reduced mass
    matrix at the same configuration (H does not depend on the velocity), so at each point they
    agree to the bit.  The matrix C^T M C is symmetric only to round-off (its (0, 1) and (1, 0)
    entries differ in the last bits at most points), so this catches terms() reading the other
    off-diagonal entry, which a tolerance would not (seed 4201 [44])."""
    exact = ExactModel(BENCH, kernel=kernel)
    rng = np.random.default_rng(44)
    for x, y in zip(rng.uniform(-0.02, 0.02, 12), rng.uniform(0.14, 0.18, 12)):
        H = exact.terms(x, y, 0.4, -0.3)[:3]
        assert H == tuple(exact.row(x, y)[:3]), (x, y)
