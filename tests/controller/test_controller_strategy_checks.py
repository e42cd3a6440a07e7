"""PositionController's check of its strategy (controller/position.py, _check_strategy) at each
parameter's boundary: the smallest value the law runs with is accepted (0 where the thesis allows
it, a small positive value where it needs > 0) and the next one below is refused, naming the
parameter and its value word for word."""
from __future__ import annotations

import re

import pytest

from controller.position import PositionController
from controller.strategies import get_strategy
from plant import get_preset

BENCH = get_preset("bench")


@pytest.mark.parametrize("name, change, message", [
    ("PDMDq", dict(gamma=(0.0, 0.25)), None),
    ("PDMDq", dict(gamma=(0.25, -1e-300)), "gamma = (0.25, -1e-300) must be >= 0"),
    ("PDMDq", dict(k=(0.0, 0.5)), None),
    ("PDMDq", dict(k=(0.5, -0.25)), "k2 = -0.25 must be >= 0"),
    ("TCx", dict(m_star=0.0), None),
    ("TCx", dict(m_star=-0.5), "m_star = -0.5 must be >= 0"),
    ("PDq", dict(m_star=1e-6), None),
    ("PDq", dict(m_star=0.0), "m_star = 0.0 must be > 0 for the PD strategy PDq"),
    ("PDq", dict(lam=1e-9), None),
    ("PDq", dict(lam=0.0), "lam = 0.0 must be > 0"),
    ("PDMDq", dict(phi=1e-9), None),
    ("PDMDq", dict(phi=-0.0), "phi = -0.0 must be > 0"),
    ("PDq", dict(space="z"), "strategy.space = 'z': valid: 'q', 'x'"),
])
def test_each_strategy_parameter_is_checked_at_its_boundary(name, change, message):
    """Catches a bound moved (gamma or k refused below 1 instead of 0, m_star's strict and loose
    bounds swapped), a parameter left unchecked, or a message naming another one."""
    strategy = get_strategy(name).with_(**change)
    if message is None:
        PositionController(BENCH, strategy)
    else:
        with pytest.raises(ValueError, match="^" + re.escape(message) + "$"):
            PositionController(BENCH, strategy)
