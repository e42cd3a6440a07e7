"""The controller's dynamic model: Ĥ and ĥ of (6.1-6.4) in task space, exact or tabulated (7.2.5).

Both models come from the plant's inverse dynamics (:func:`plant.parallel.inverse_dynamics_terms`,
5.74-5.77) with q# = (x, y)::

    H(x) ddx + h(x, dx) = Z^T u*,   H = M_M (5.75, 6.1),   h = v_M + g_M (5.76-5.77, 6.2)

``v_M`` is exactly quadratic in dx (the velocity terms of the serial chains and the
constraint bias c of 5.69 are quadratic forms in the quasi-velocities), so
``v_M(x, dx) = cxx(x) dx^2 + cyy(x) dy^2 + cxy(x) dx dy`` with 2-vectors obtained from
three evaluations at dx = (1, 0), (0, 1), (1, 1):
``cxx = v(1,0)``, ``cyy = v(0,1)``, ``cxy = v(1,1) - v(1,0) - v(0,1)``.

:class:`ExactModel` evaluates (5.74-5.77) at every call: with the compiled 5R kernel
(:func:`plant.fast5r.inverse_terms`, default, a few µs) or the general numpy algorithm
(``kernel="general"``, ~2 ms; the reference).  :class:`TabulatedModel` stores H (3 entries),
the six quadratic coefficients and g on a square grid (default 5 mm, thesis 7.2.5) and
interpolates bilinearly (the C kernel's ``pc_law_interpolate``, which the law uses too).
Grid points outside the workspace or in the near-singular band
(margin < :data:`plant.fivebar.NEAR_SINGULAR_MARGIN`) are left out; asking for a point
whose cell has a missing corner raises :class:`ModelRangeError`.

The joint-space terms follow by the change of variables x = FK(q) of
:mod:`controller.kinematics` (no second dynamic model): with ``dx = J dq`` and
``ddx = J ddq + beta``, ``H_q = J^T H J`` and ``h_q = J^T (H beta + h)``; the actuator
torques are then the joint-space efforts themselves.

``model_error`` e builds the model from parameters whose masses, link inertias and rotor
inertias are scaled by (1 + e) (:func:`perturbed_params`).
"""
from __future__ import annotations

import hashlib
import math
import os
import threading
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

import kernels
from plant import fivebar
from plant.fast5r import INVERSE_SIZE, inverse_terms, pack_params
from plant.parallel import inverse_dynamics_terms
from plant.presets import FiveBarParams

from . import law
from .kinematics import Kinematics

#: Entries of one table row: H00, H01, H11, cxx(2), cyy(2), cxy(2), g(2).
N_TERMS = law.N_TERMS
DEFAULT_GRID_STEP = 0.005
#: Default tabulated region (x_min, x_max, y_min, y_max), m: covers the bench and simulation
#: trajectories (thesis 7.18, 7.23-7.26) with margin; pass ``extent="workspace"`` for all of
#: the upper half-plane workspace.
DEFAULT_EXTENT = (-0.12, 0.12, 0.06, 0.29)
#: Implementations of the exact model: the compiled 5R kernel or the general algorithm.
EXACT_KERNELS = ("fast", "general")


class ModelRangeError(ValueError):
    """The model has no value at the requested point."""


def perturbed_params(params: FiveBarParams, model_error: float) -> FiveBarParams:
    """Parameters with every mass (counter-masses too, which keeps them where they balance),
    link inertia and rotor inertia scaled by (1 + model_error).

    Raises
    ------
    ValueError
        If ``model_error`` is not finite or <= -1.
    """
    if not (math.isfinite(model_error) and model_error > -1.0):
        raise ValueError(f"model_error = {model_error!r} must be finite and > -1")
    f = 1.0 + float(model_error)

    def chain(c):
        return replace(c, m1=c.m1 * f, m2=c.m2 * f, Jz1=c.Jz1 * f, Jz2=c.Jz2 * f, J_rotor=c.J_rotor * f,
                       counter_mass1=c.counter_mass1 * f, counter_mass2=c.counter_mass2 * f)

    return replace(params, chain1=chain(params.chain1), chain2=chain(params.chain2), m0=params.m0 * f)


class ExactModel:
    """Ĥ, ĥ from the inverse dynamics (5.74-5.77) at every call.

    Parameters
    ----------
    params : FiveBarParams
        The model's parameters (already perturbed if wanted).
    kernel : {"fast", "general"}
        :func:`plant.fast5r.inverse_terms` (compiled, the 5R specialisation) or
        :func:`plant.parallel.inverse_dynamics_terms` (the general algorithm); equal to
        round-off (``tests/controller/test_controller_fast.py``).
    """

    kind = "exact"

    def __init__(self, params: FiveBarParams, kernel="fast"):
        if kernel not in EXACT_KERNELS:
            raise ValueError(f"kernel = {kernel!r} is unknown; valid: {', '.join(EXACT_KERNELS)}")
        self.params, self.kernel = params, kernel
        self.mechanism = fivebar.build_mechanism(params)
        self.kin = Kinematics(params)
        self.last_Z = None
        self._p = pack_params(params)
        self._out = np.empty(INVERSE_SIZE)

    def _terms(self, q, dq):
        """(M_M, v_M, g_M, Z) of (5.74) at (q, dq) with the chosen kernel."""
        if self.kernel == "general":
            t = inverse_dynamics_terms(self.mechanism, q, dq)
            return t.M, t.v, t.g, t.Z
        out = self._out
        inverse_terms(self._p, q, dq, out)
        return out[0:4].reshape(2, 2).copy(), out[4:6].copy(), out[6:8].copy(), out[8:12].reshape(2, 2).copy()

    def full_state(self, x, y, dx, dy):
        """Consistent thesis coordinates q (7.12) and dq = C dq# (5.56) for (x, y, dx, dy)."""
        return self.kin.thesis_state(x, y, dx, dy)

    def terms(self, x, y, dx, dy):
        """(H00, H01, H11, h0, h1) at (x, y, dx, dy); also keeps Z of (5.72) in ``last_Z``."""
        q, dq = self.full_state(x, y, dx, dy)
        if self.kernel == "general":
            t = inverse_dynamics_terms(self.mechanism, q, dq)
            self.last_Z = t.Z
            h = t.v + t.g
            return float(t.M[0, 0]), float(t.M[0, 1]), float(t.M[1, 1]), float(h[0]), float(h[1])
        out = self._out
        inverse_terms(self._p, q, dq, out)
        self.last_Z = out[8:12].reshape(2, 2).copy()
        M00, M01, _, M11, v0, v1, g0, g1 = out[:8].tolist()
        return M00, M01, M11, v0 + g0, v1 + g1

    def row(self, x, y):
        """One table row (N_TERMS values) at (x, y): H, the quadratic coefficients and g."""
        q, _ = self.full_state(x, y, 0.0, 0.0)
        values = []
        for ux, uy in ((1.0, 0.0), (0.0, 1.0), (1.0, 1.0)):
            _, dq = self.full_state(x, y, ux, uy)
            M, v, g, _ = self._terms(q, dq)
            values.append(v)
        vx, vy, vxy = values
        return np.concatenate([[M[0, 0], M[0, 1], M[1, 1]], vx, vy, vxy - vx - vy, g])


def _grid_size(extent, step):
    """(nx, ny): the grid lines of ``extent`` at ``step``."""
    x0, x1, y0, y1 = extent
    return int(round((x1 - x0) / step)) + 1, int(round((y1 - y0) / step)) + 1


def _grid(extent, step):
    nx, ny = _grid_size(extent, step)
    return extent[0] + step * np.arange(nx), extent[2] + step * np.arange(ny)


def workspace_extent(params: FiveBarParams):
    """Bounding box of the upper half-plane workspace (y >= 0), m."""
    reach = max(params.chain1.l1 + params.chain1.l2, params.chain2.l1 + params.chain2.l2)
    return (-params.l0 - reach, params.l0 + reach, 0.0, reach)


def build_table(params: FiveBarParams, step=DEFAULT_GRID_STEP, extent=DEFAULT_EXTENT,
                band=fivebar.NEAR_SINGULAR_MARGIN, kernel="fast"):
    """Evaluate the model on the grid (7.2.5), with :class:`ExactModel` (``kernel``).

    Returns
    -------
    xs, ys : numpy.ndarray
        Grid lines, m.
    table : numpy.ndarray
        Shape (ny, nx, N_TERMS); NaN at left-out points.
    """
    exact = ExactModel(params, kernel)
    xs, ys = _grid(extent, step)
    table = np.full((ys.size, xs.size, N_TERMS), np.nan)
    for iy, y in enumerate(ys):
        for ix, x in enumerate(xs):
            try:
                if exact.kin.margin(x, y) < band:
                    continue
            except fivebar.KinematicsError:
                continue
            table[iy, ix] = exact.row(x, y)
    return xs, ys, table


def cache_dir() -> Path:
    """Where tables are cached: ``$PARCOSIM_CACHE`` or ``$XDG_CACHE_HOME/parcosim`` (~/.cache/parcosim)."""
    root = os.environ.get("PARCOSIM_CACHE")
    if root:
        return Path(root)
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "parcosim"


#: Serialises loading and building tables (:class:`TabulatedModel`).
_TABLE_LOCK = threading.RLock()


def _load_table(path: Path):
    """(xs, ys, table) from the cache file ``path``; None if there is none, or (with a
    warning naming the file) if it cannot be read or is not a table."""
    if not path.exists():
        return None
    try:
        with np.load(path) as data:
            xs, ys, table = data["xs"], data["ys"], data["table"]
        if xs.ndim != 1 or ys.ndim != 1 or table.shape[:2] != (ys.size, xs.size) or xs.size < 2 or ys.size < 2:
            raise ValueError(f"shapes xs {xs.shape}, ys {ys.shape}, table {table.shape} do not fit")
        return xs, ys, table
    except Exception as exc:  # noqa: BLE001 - any unreadable cache file is rebuilt
        warnings.warn(f"controller table cache {path} is unreadable ({type(exc).__name__}: {exc}); "
                      "rebuilding the table", stacklevel=3)
        return None


def _save_table(path: Path, xs, ys, table) -> None:
    """Write the table to ``path`` atomically; on failure warn naming the file and keep
    the table in memory only."""
    tmp = path.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp.npz")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(tmp, xs=xs, ys=ys, table=table)
        os.replace(tmp, path)
    except OSError as exc:
        warnings.warn(f"controller table cache {path} cannot be written ({exc}); the table stays in memory",
                      stacklevel=3)
        try:
            tmp.unlink()
        except OSError:
            pass


#: Tables computed ahead, :func:`_cache_key` -> (xs, ys, table): an FMU's, built when the FMU
#: was built for its parameters then and loaded from its resources (:mod:`fmus.slave.designs`), so
#: that starting it builds no table and reads no user cache.  While an FMU is built
#: (``RECORDING``), each table made or loaded is added.
PRECOMPUTED = {}
RECORDING = False


def _cache_key(params, step, extent, band):
    # The kernels' code version: a table is the C exact model's output, and a kernel change
    # (e.g. its sin and cos) moves it by round-off, which a cached table would hide.
    text = repr((params, float(step), tuple(float(e) for e in extent), float(band), N_TERMS, kernels.code_version()))
    return hashlib.sha256(text.encode()).hexdigest()[:20]


class TabulatedModel:
    """Ĥ, ĥ interpolated bilinearly on a grid over the workspace (7.2.5).

    Parameters
    ----------
    params : FiveBarParams
        The model's parameters (already perturbed if wanted).
    step : float
        Grid step, m (thesis: 5 mm).
    extent : tuple or "workspace"
        (x_min, x_max, y_min, y_max) of the grid, m.
    cache : bool
        Load the table from / save it to :func:`cache_dir` (``np.savez``), keyed by a
        hash of the parameters, step, extent and band.  A table of :data:`PRECOMPUTED`
        (an FMU's own) is taken before either.

    Attributes
    ----------
    build_seconds : float
        Wall time spent building (0 when loaded from the cache or :data:`PRECOMPUTED`).
    """

    kind = "tabulated"
    #: The kernel's table is configuration: a restored FMU state may not change a word of it.
    KERNEL_BUFFERS = {"kernel_table": lambda buf: ()}

    def __init__(self, params: FiveBarParams, step=DEFAULT_GRID_STEP, extent=DEFAULT_EXTENT,
                 cache=True, band=fivebar.NEAR_SINGULAR_MARGIN):
        if not (math.isfinite(step) and step > 0.0):
            raise ValueError(f"grid step = {step!r} m must be > 0")
        if isinstance(extent, str):
            if extent != "workspace":
                raise ValueError(f"extent = {extent!r}: give (x_min, x_max, y_min, y_max) or 'workspace'")
            extent = workspace_extent(params)
        extent = tuple(float(e) for e in extent)
        if not (extent[1] > extent[0] and extent[3] > extent[2]):
            raise ValueError(f"extent = {extent!r} is empty")
        nx, ny = _grid_size(extent, step)
        if nx < 2 or ny < 2:    # a cell needs 2 lines a side (a 1-line table would be cached, then refused on load)
            raise ValueError(f"grid step = {step!r} m over extent = {extent!r} gives {nx} x {ny} grid points: the "
                             "table interpolates in cells of 2 x 2 points")
        self.params, self.step, self.extent = params, float(step), extent
        self.build_seconds = 0.0
        key = _cache_key(params, step, extent, band)
        path = cache_dir() / f"model_{key}.npz" if cache else None
        with _TABLE_LOCK:   # one build per table, also with controllers initialised from two threads
            loaded = PRECOMPUTED.get(key)
            if loaded is not None:
                loaded = tuple(a.copy() for a in loaded)
            elif path is not None:
                loaded = _load_table(path)
            if loaded is not None:
                xs, ys, table = loaded
            else:
                start = time.perf_counter()
                xs, ys, table = build_table(params, step, extent, band)
                self.build_seconds = time.perf_counter() - start
                if path is not None:
                    _save_table(path, xs, ys, table)
            if RECORDING:
                PRECOMPUTED[key] = (xs.copy(), ys.copy(), table.copy())
        self.xs, self.ys = xs, ys
        # The kernel's pc_law_table; ``table`` is its values' view (shape (ny, nx, N_TERMS)).
        self.kernel_table = law.pack_table(float(xs[0]), float(ys[0]), self.step, table)
        self.table = law.table_values(self.kernel_table, table.shape)
        valid = ~np.isnan(table[:, :, 0])
        self.valid = valid
        self.cell_ok = valid[:-1, :-1] & valid[1:, :-1] & valid[:-1, 1:] & valid[1:, 1:]

    def interpolate(self, x, y):
        """The N_TERMS table values at (x, y), bilinear in the grid cell (7.2.5).

        Raises
        ------
        ModelRangeError
            If (x, y) is outside the grid or a corner of its cell was left out.
        """
        out = np.empty(N_TERMS)
        code, _ = law.interpolate(self.kernel_table, x, y, out)
        if code != law.OK:
            raise ModelRangeError(self.refusal_text(code, x, y))
        return out

    def refusal_text(self, code, x, y) -> str:
        """Why the table has no value at (x, y) (``code``: law.TABLE_OUT or law.TABLE_HOLE)."""
        if code == law.TABLE_OUT:
            return (f"point (x={x:.6g}, y={y:.6g}) m is outside the tabulated region "
                    f"x in [{self.extent[0]:g}, {self.extent[1]:g}], y in [{self.extent[2]:g}, {self.extent[3]:g}] m")
        return (f"point (x={x:.6g}, y={y:.6g}) m needs a grid point left out of the table "
                f"(outside the workspace or near-singular)")

    def terms(self, x, y, dx, dy):
        """(H00, H01, H11, h0, h1) at (x, y, dx, dy) from the interpolated table."""
        H00, H01, H11, a0, a1, b0, b1, c0, c1, g0, g1 = self.interpolate(x, y).tolist()
        xx, yy, xy = dx * dx, dy * dy, dx * dy
        return H00, H01, H11, a0 * xx + b0 * yy + c0 * xy + g0, a1 * xx + b1 * yy + c1 * xy + g1


def tabulation_error(table: TabulatedModel, samples=400, seed=0):
    """Error of the interpolated table against :class:`ExactModel` at random points.

    Points are drawn uniformly in the table's cells whose four corners are present.
    Returns a dict: ``H`` max |Ĥ_tab - Ĥ| / max|Ĥ| (entrywise, relative to the largest
    entry of the exact Ĥ at that point), ``h`` the same for ĥ at |dx| = 1 m/s in a random
    direction (relative to max |ĥ|), ``H_median``, ``H_p99``, ``h_median``, ``h_p99`` the
    median and 99th percentile over the points (the maximum sits in the cells next to the
    near-singular band, where the terms vary fastest), ``points`` the number of points.
    """
    rng = np.random.default_rng(seed)
    exact = ExactModel(table.params)
    cells = np.argwhere(table.cell_ok)
    if cells.size == 0:
        raise ValueError("the table has no complete cell")
    errs_H, errs_h = [], []
    for iy, ix in cells[rng.integers(0, len(cells), samples)]:
        x = table.xs[ix] + rng.random() * table.step
        y = table.ys[iy] + rng.random() * table.step
        angle = rng.random() * 2 * math.pi
        dx, dy = math.cos(angle), math.sin(angle)
        e = np.array(exact.terms(x, y, dx, dy))
        t = np.array(table.terms(x, y, dx, dy))
        errs_H.append(np.abs(t[:3] - e[:3]).max() / np.abs(e[:3]).max())
        errs_h.append(np.abs(t[3:] - e[3:]).max() / np.abs(e[3:]).max())
    result = {"points": int(samples)}
    for name, errs in (("H", errs_H), ("h", errs_h)):
        result[name] = float(np.max(errs))
        result[f"{name}_median"] = float(np.median(errs))
        result[f"{name}_p99"] = float(np.percentile(errs, 99))
    return result
