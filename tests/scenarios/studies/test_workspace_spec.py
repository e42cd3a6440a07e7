"""scenarios/studies/workspace/spec.py, the workspace slice of any mechanism spec, on the bench 5R's
spec against the 5R's closed-form workspace (:func:`plant.fivebar.workspace_map` on the same
grid, an independent computation) and the chains' reach written here: every point the slice
assembles is one the closed form assembles and both chains reach; each status follows from the
margin; the assembled points are one connected region around the start; the slice's files
read back (issue 31: the scenarios' weakest area; a design compared with an independent
computation).  A coarse grid (11 x 11) keeps it fast."""
from __future__ import annotations

import json

import numpy as np
import pytest

from plant import fivebar, get_preset
from plant import spec as plant_spec
from scenarios.studies.workspace import spec as ws_spec
from scenarios.studies.workspace.figure import thesis_trajectories

EXTENT = (-0.2, 0.3, -0.05, 0.45)
BAND = 0.1


@pytest.fixture(scope="module")
def sliced():
    spec = plant_spec.load("bench_5r")
    grid, ws_spec.SPEC_GRID = ws_spec.SPEC_GRID, 11
    try:
        ws, serial, parallel = ws_spec.slice_map(spec, BAND, extent=EXTENT)
    finally:
        ws_spec.SPEC_GRID = grid
    return spec, ws, serial, parallel


def test_every_point_of_the_slice_is_one_the_closed_form_assembles_and_both_chains_reach(sliced):
    """Catches a point kept where Newton failed or that no 5R of these links can reach, a grid
    other than the extent's, and a slice that assembles almost nothing."""
    spec, ws, _, _ = sliced
    step = (EXTENT[1] - EXTENT[0]) / 10
    closed = fivebar.workspace_map(get_preset("bench"), step=step, extent=EXTENT)
    assert np.allclose(closed.x, ws.x, atol=1e-12) and np.allclose(closed.y, ws.y, atol=1e-12)
    inside = ws.status != ws.OUTSIDE
    assert np.count_nonzero(inside) >= 10 and not np.any(inside & (closed.status == closed.OUTSIDE))
    for chain in spec.chains:
        a1, a2 = (j.a for j in chain.chain.joints)
        for iy, ix in zip(*np.nonzero(inside)):
            r = np.hypot(ws.x[ix] - chain.base[0], ws.y[iy] - chain.base[1])
            assert abs(a1 - a2) - 1e-12 <= r <= a1 + a2 + 1e-12, (ws.x[ix], ws.y[iy])


def test_each_status_follows_from_the_smaller_measure_and_the_band(sliced):
    """Catches the margin taken as the larger measure, the band compared the wrong way, and a
    point with measures left OUTSIDE."""
    _, ws, serial, parallel = sliced
    margin = np.fmin(serial, parallel)
    assert np.array_equal(ws.margin, margin, equal_nan=True)
    assert np.array_equal(ws.status == ws.OUTSIDE, np.isnan(margin))
    known = ~np.isnan(margin)
    assert np.array_equal(ws.status[known] == ws.NEAR_SINGULAR, margin[known] < BAND)
    assert np.all((0.0 <= margin[known]) & (margin[known] <= 1.0))


def test_the_slice_is_one_region_grown_from_the_start(sliced):
    """Every assembled point is reached from the start's grid point through assembled
    neighbours.  Catches a start point other than the grid's nearest, and a fill that
    jumps."""
    spec, ws, _, _ = sliced
    inside = ws.status != ws.OUTSIDE
    start = (int(np.argmin(np.abs(ws.y - spec.start[1]))), int(np.argmin(np.abs(ws.x - spec.start[0]))))
    assert inside[start]
    seen, todo = {start}, [start]
    while todo:
        iy, ix = todo.pop()
        for dy, dx in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            n = (iy + dy, ix + dx)
            if 0 <= n[0] < ws.y.size and 0 <= n[1] < ws.x.size and inside[n] and n not in seen:
                seen.add(n)
                todo.append(n)
    assert len(seen) == np.count_nonzero(inside)


@pytest.mark.parametrize("name, preset", [("bench_5r", "bench"), ("thesis_sim_5r", "thesis_sim")])
def test_the_default_extent_is_the_longest_reach_around_the_start(monkeypatch, name, preset):
    """Without an extent the slice spans the start ± the longest chain's reach from the origin
    (its links l1 + l2 plus its base, l0 from the middle, of the 5R's own parameters), on
    SPEC_GRID points per axis, and still assembles the start.  Catches the extent's centre or
    half-width of another term (the base subtracted, the start left out) and an axis swapped."""
    monkeypatch.setattr(ws_spec, "SPEC_GRID", 11)
    spec, p = plant_spec.load(name), get_preset(preset)
    reach = max(c.l1 + c.l2 for c in (p.chain1, p.chain2)) + p.l0
    ws, _, _ = ws_spec.slice_map(spec, BAND)
    x0, y0 = spec.start[0], spec.start[1]
    np.testing.assert_allclose(ws.x, np.linspace(x0 - reach, x0 + reach, 11), rtol=0, atol=1e-15)
    np.testing.assert_allclose(ws.y, np.linspace(y0 - reach, y0 + reach, 11), rtol=0, atol=1e-15)
    start = (int(np.argmin(np.abs(ws.y - y0))), int(np.argmin(np.abs(ws.x - x0))))
    assert ws.status[start] != ws.OUTSIDE


def test_the_figure_and_json_of_a_spec_and_a_serial_spec_refused(tmp_path, monkeypatch):
    """plot_spec_slice's JSON read back: the mechanism, band, grid step, points inside and each
    thesis trajectory's verdict as its own summary.  Catches a count of another status, the
    step of another axis, a trajectory left out or sampled over part of its duration or at
    another step; a serial spec refused naming its file."""
    monkeypatch.setattr(ws_spec, "SPEC_GRID", 11)
    report = ws_spec.plot_spec_slice("bench_5r", tmp_path, BAND)
    text = (tmp_path / "workspace.json").read_text()
    data = json.loads(text)
    assert text == json.dumps(data, indent=2) + "\n"          # the results' JSON form: indented, a final newline
    assert (tmp_path / "workspace.png").stat().st_size > 0 and report.png == tmp_path / "workspace.png"
    spec = plant_spec.load("bench_5r")
    ws, _, _ = ws_spec.slice_map(spec, BAND)
    assert data["mechanism"] == "bench_5r" == report.mechanism and data["band"] == BAND
    assert data["step"] == float(ws.x[1] - ws.x[0])
    assert data["points_inside"] == int(np.count_nonzero(ws.status != ws.OUTSIDE))
    assert data["trajectories"] == [json.loads(json.dumps(c.summary())) for c in report.trajectories]
    expected = {**thesis_trajectories("thesis_sim"), **thesis_trajectories("bench")}
    assert [t["name"] for t in data["trajectories"]] == list(expected) and len(expected) >= 2
    for check in report.trajectories:    # each reference sampled every 1 ms over its whole duration
        ref = expected[check.name]
        ts = np.arange(int(round(ref.duration / check.sample_time)) + 1) * check.sample_time
        assert ts[-1] == pytest.approx(ref.duration) and check.sample_time == 1e-3
        path = np.array([tuple(ref(t))[:2] for t in ts])
        np.testing.assert_array_equal(check.x, path[:, 0])
        np.testing.assert_array_equal(check.y, path[:, 1])
    with pytest.raises(ValueError, match=r"rr\.toml: a serial chain \(no \[platform\]\) has no parallel workspace"):
        ws_spec.plot_spec_slice("rr", tmp_path, BAND)


def test_each_trajectory_point_takes_the_status_and_margin_of_its_nearest_grid_point_edges_included():
    """``_check_on_grid`` on a 4 x 3 map made up here, every node's status and margin its own: a
    path sampled at 1 ms through the map's four corners and beyond each edge takes the nearest
    node's (found here by argmin of the distances; a point beyond an edge takes the edge's node).
    The edge rows and columns differ from their neighbours.  Catches the last row or column
    never looked up (an index clipped one short, seed 3901 [198]), the axes swapped, and a
    wrong nearest node."""
    xs, ys = np.array([0.0, 0.01, 0.02, 0.03]), np.array([0.1, 0.11, 0.12])
    O, I, B = fivebar.WorkspaceMap.OUTSIDE, fivebar.WorkspaceMap.INSIDE, fivebar.WorkspaceMap.NEAR_SINGULAR
    status = np.array([[B, I, I, O],
                       [I, I, I, B],
                       [O, B, I, B]])
    margin = np.where(status == O, np.nan, 0.1 * np.arange(1, 13).reshape(3, 4))
    ws = fivebar.WorkspaceMap(xs, ys, margin, status)
    path = [(-0.005, 0.095), (0.0, 0.12), (0.031, 0.1249), (0.04, 0.099), (0.0149, 0.1149), (0.026, 0.2),
            (0.019, 0.09)]
    check = ws_spec._check_on_grid(ws, "made up", lambda t: path[int(round(t / 1e-3))] + (0.0,), 6e-3)
    near = [(int(np.argmin(np.abs(ys - min(max(y, ys[0]), ys[-1])))),
             int(np.argmin(np.abs(xs - min(max(x, xs[0]), xs[-1]))))) for x, y in path]
    assert np.array_equal(check.x, [x for x, _ in path]) and np.array_equal(check.y, [y for _, y in path])
    expected = {kind: [k for k, (iy, ix) in enumerate(near) if status[iy, ix] == code]
                for kind, code in ((ws_spec.OUTSIDE, O), (ws_spec.BAND, B))}
    assert {k: v.tolist() for k, v in check.refused.items()} == expected
    assert expected[ws_spec.OUTSIDE] == [1, 3] and expected[ws_spec.BAND] == [0, 2, 5]      # by hand: the corners
    assert check.min_margin == min(margin[iy, ix] for iy, ix in near if not np.isnan(margin[iy, ix]))


def test_the_figure_draws_each_locus_as_its_own_measure_at_the_level_its_label_states(tmp_path, monkeypatch):
    """The loci are the zero contours of the fields handed to ``draw``: each field is its own
    measure of the slice (parallel for the first, serial for the second, as the labels name
    them) less the level the label states, NaN exactly where the slice did not assemble.
    (On the default extent's coarse 11 x 11 grid the slice may assemble little more than the
    start: enough to tell.)  Catches the fields swapped, a NaN field (the NaN/difference branches of ``np.where``
    swapped: no locus drawn), and a level other than the label's."""
    import re

    monkeypatch.setattr(ws_spec, "SPEC_GRID", 11)
    drawn = []
    monkeypatch.setattr(ws_spec, "draw", lambda *args, **kw: drawn.append((args, kw)))
    ws_spec.plot_spec_slice("bench_5r", tmp_path, BAND)
    _, serial, parallel = ws_spec.slice_map(plant_spec.load("bench_5r"), BAND)
    ((args, kw),) = drawn
    for field, measure, label, name in zip(args[1:3], (parallel, serial), kw["labels"], ("parallel", "serial")):
        level = float(re.fullmatch(name + r" measure = ([0-9.e-]+)", label).group(1))
        assert np.array_equal(np.isnan(field), np.isnan(measure)) and not np.all(np.isnan(field))
        np.testing.assert_allclose(field + level, measure, rtol=0, atol=1e-15)
