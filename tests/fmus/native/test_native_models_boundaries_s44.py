"""The PositionController's native build data: its strategy table row by row against
controller/strategies.py (fmus/native/models.py ``_position``; issue 31, training seed 4452 [22]).

Each row is one (trajectory, strategy): space (0 joint, 1 task), model-based, lam, m*, phi, the
two gains k, then the optional gamma as a flag and its two values (0, 0, 0 when the
strategy has none), then the law (0 unified, 1 seed 001's).
"""
from __future__ import annotations

import numpy as np

from controller.strategies import get_strategy
from fmus.native.models import NATIVE
from tests.fmus.slave.test_extremes import make_slave


def test_each_strategy_row_is_the_strategys_fields_with_no_gamma_written_as_a_zero_flag():
    """Rows in the order of the trajectory and strategy names carried, each recomputed here from
    :func:`get_strategy`; a strategy without gamma (all of today's) has flag and values zero."""
    scalars, arrays = NATIVE["PositionController"].data(make_slave("PositionController"))
    expected = []
    for trajectory in arrays["trajectory_names"]:
        for name in arrays["strategy_names"]:
            s = get_strategy(name, trajectory)
            gamma = [0.0, 0.0, 0.0] if s.gamma is None else [1.0, *s.gamma]
            expected.append([1.0 if s.space == "x" else 0.0, 1.0 if s.model_based else 0.0, s.lam, s.m_star, s.phi,
                             *s.k, *gamma, 1.0 if s.law == "seed001" else 0.0])
    assert scalars["strategy_words"] == len(expected[0])
    np.testing.assert_array_equal(arrays["strategies"], np.array(expected))
