"""The 5R model's set-up in C (kernels/src/model5r.c: the native PositionController makes its
model with it at set-up) against the Python the pythonfmu twin uses as the oracle: the chains
with counter-masses (plant.fast5r.pack_params of plant.presets' counter_offsets and
composite_link) and the tabulated model (controller.model.TabulatedModel's kernel_table, built
afresh, no cache), bit for bit, for several presets, gravities, counter-masses, model errors,
grid steps and extents."""
import ctypes
from dataclasses import replace

import numpy as np
import pytest

import kernels
from controller.model import DEFAULT_EXTENT, TabulatedModel, perturbed_params
from plant import fivebar
from plant.fast5r import CHAIN, CHAIN_SIZE, PARAMS, pack_params
from plant.presets import get_preset

_p, _d, _l = ctypes.c_void_p, ctypes.c_double, ctypes.c_long
_pack_chain = kernels.function("pc_model5r_pack_chain", None, _p, _d, _d)
_table_words = kernels.function("pc_model5r_table_words", _l, _p, _d, ctypes.POINTER(_l), ctypes.POINTER(_l))
_build_table = kernels.function("pc_model5r_build_table", _l, _p, _p, _d, _d, _p, _l)
FIELDS = ("l1", "l2", "lg1", "lg2", "m1", "m2", "Jz1", "Jz2", "J_rotor")


def model_params(preset="bench", gravity=(0.0, 0.0), masses=(0.0, 0.0), error=0.0):
    """The controller's model as the pythonfmu PositionController makes it."""
    params = replace(get_preset(preset), gravity=(*gravity, 0.0)).with_counter_masses(*masses)
    return perturbed_params(params, error)


def c_chain(chain, masses) -> np.ndarray:
    """pc_model5r_pack_chain of the chain's own fields and counter-masses."""
    buf = np.zeros(CHAIN_SIZE)
    for name in FIELDS:
        buf[CHAIN[name]] = getattr(chain, name)
    _pack_chain(buf.ctypes.data, *masses)
    return buf


def c_table(params, step, extent, band=fivebar.NEAR_SINGULAR_MARGIN):
    p, e = pack_params(params), np.array(extent, dtype=np.float64)
    nx, ny = _l(), _l()
    words = _table_words(e.ctypes.data, step, ctypes.byref(nx), ctypes.byref(ny))
    table = np.full(words, 7.0)
    points = _build_table(p.ctypes.data, e.ctypes.data, step, band, table.ctypes.data, words)
    assert _build_table(p.ctypes.data, e.ctypes.data, step, band, np.zeros(words - 1).ctypes.data, words - 1) == -1
    return table, points, (nx.value, ny.value)


MODELS = [
    ("bench", (0.0, 0.0), (0.0, 0.0), 0.0),
    ("bench", (0.0, -9.81), (0.4, 0.25), 0.0),
    ("bench", (1.5, -9.81), (0.4, 0.0), 0.1),
    ("thesis_sim", (0.0, 0.0), (0.0, 0.3), -0.25),
    ("thesis_sim", (0.0, -9.81), (0.5, 0.2), 0.37),
]


@pytest.mark.parametrize("preset, gravity, masses, error", MODELS)
def test_chains_with_counter_masses_are_pack_params_bit_for_bit(preset, gravity, masses, error):
    """Catches an offset of the wrong link (L1 carries link 2 and its counter-mass at the elbow),
    the parallel-axis terms summed otherwise, a counter-mass of 0 that moves its link."""
    model = model_params(preset, gravity, masses, error)
    packed = pack_params(model)[PARAMS["chain"]]
    for k, chain in enumerate((model.chain1, model.chain2)):
        got = c_chain(chain, (chain.counter_mass1, chain.counter_mass2))
        assert got.tobytes() == packed[k * CHAIN_SIZE:(k + 1) * CHAIN_SIZE].tobytes(), (k, got, packed)


@pytest.mark.parametrize("preset, gravity, masses, error", MODELS)
@pytest.mark.parametrize("step, extent", [(0.005, DEFAULT_EXTENT), (0.0085, (-0.2, 0.13, 0.02, 0.31)),
                                          (0.003, (-0.05, 0.07, 0.1, 0.2))])
def test_table_is_tabulated_models_kernel_table_bit_for_bit(preset, gravity, masses, error, step, extent):
    """The header (first point, 1 / step, cells), every row of every point tabulated, NaN at the
    same left-out points (out of reach or in the near-singular band).  Catches a grid point
    count rounded otherwise, rows in another order, the quadratic coefficients' cross term
    composed otherwise, the band's test inverted, H or g from the wrong evaluation."""
    model = model_params(preset, gravity, masses, error)
    reference = TabulatedModel(model, step, extent, cache=False).kernel_table
    table, points, (nx, ny) = c_table(model, step, extent)
    assert table.size == reference.size
    assert np.isnan(table).tobytes() == np.isnan(reference).tobytes()
    assert table[~np.isnan(table)].tobytes() == reference[~np.isnan(reference)].tobytes()
    values = table[5:].reshape(ny, nx, -1)
    assert points == int((~np.isnan(values[:, :, 0])).sum()) and 0 < points <= nx * ny
    assert points < nx * ny or extent[0] > -0.1   # the wide grids leave points out
