"""The strategy a PositionController slave builds from its parameters (``setup``): the preset
of Tables 6-8 where a parameter is left at its default (-1 for lam, m_star, phi, k1, k2; 0 for
the adaptation rates gamma1, gamma2: "0: constant gain", the preset's non-adaptive law), the
value given otherwise, each read back exactly from the controller's strategy."""
from __future__ import annotations

import pytest

from controller.strategies import get_strategy
from fmus.slaves.parcosim_positioncontroller import PositionController

STRATEGY = "SMCx"


def _strategy(**parameters):
    slave = PositionController(instance_name="ctrl")
    slave.strategy, slave.model = STRATEGY, "exact"      # exact: no table to build
    for name, value in parameters.items():
        setattr(slave, name, value)
    slave.setup()
    return slave.controller.strategy, get_strategy(STRATEGY, slave.trajectory)


def test_the_defaults_build_the_presets_strategy_with_constant_gains():
    """Catches rates of 0 taken as an adaptive law (gamma (0, 0) in place of the preset's none)."""
    built, preset = _strategy()
    assert preset.gamma is None and built.gamma is None
    assert (built.lam, built.m_star, built.phi, tuple(built.k)) == (preset.lam, preset.m_star, preset.phi,
                                                                   tuple(preset.k))


@pytest.mark.parametrize("gamma", [(0.5, 0.0), (0.0, 0.25), (0.5, 0.25)])
def test_either_adaptation_rate_above_zero_makes_the_gains_adaptive_with_both_rates(gamma):
    built, _ = _strategy(gamma1=gamma[0], gamma2=gamma[1])
    assert built.gamma == gamma


def test_each_given_gain_replaces_the_presets_and_the_others_stay():
    built, preset = _strategy(lam=7.5, k2=0.125)
    assert built.lam == 7.5 and tuple(built.k) == (preset.k[0], 0.125)
    assert (built.m_star, built.phi) == (preset.m_star, preset.phi)


@pytest.mark.parametrize("name, value, refused", [
    ("gamma1", -1.0, True), ("gamma2", -1e-3, True), ("kt1", -0.5, True), ("kt2", -2.0, True),
    ("kt1", -1.0, False), ("kt2", -1.0, False), ("gamma2", 0.0, False),
])
def test_a_negative_rate_or_torque_constant_is_refused_but_the_presets_minus_one_of_kt(name, value, refused):
    """-1 means "the motor preset's" for kt1, kt2 only; an adaptation rate has no preset
    value, so -1 there is refused like any negative one."""
    if refused:
        with pytest.raises(ValueError, match=rf"^parameter {name} = {value!r} must be >= 0$"):
            _strategy(**{name: value})
    else:
        _strategy(**{name: value})
