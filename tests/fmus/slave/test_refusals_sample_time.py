"""A sample time T below the shortest step (:data:`fmus.slave.base.MIN_STEP`) yet above the absurd
(:data:`fmus.slave.refusals.TINY`) is refused at initialisation by every model with a parameter T, in
the same words, and T = MIN_STEP is not (issue 31: each bound on both sides, the message word for word)."""
from __future__ import annotations

import pytest

from fmus.slave.base import MIN_STEP
from fmus.slave.refusals import TINY
from tests.fmus.slave.test_extremes import GOOD, set_variables, slave_class

MODELS = ("DCMotorDrive", "CurrentObserver", "PositionController", "BalanceController", "ActuatedFiveBarPlant")


def _initialised(model, T):
    slave = slave_class(model)(instance_name=model)
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    set_variables(slave, {**GOOD.get(model, ({},))[0], "T": T}, initialise=False)
    slave.exit_initialization_mode()
    return slave


@pytest.mark.parametrize("model", MODELS)
def test_a_sample_time_below_the_shortest_step_is_refused_naming_it(model):
    """Catches the bound's test made never true (T below 1 ns taken: a sampled model then asks for
    steps no master takes) or moved (T = 1 ns refused)."""
    assert TINY < 0.5 * MIN_STEP
    short = _initialised(model, 0.5 * MIN_STEP)
    assert f"parameter T = {0.5 * MIN_STEP!r} s must be >= {MIN_STEP:g} s" in short.error, short.error
    at = _initialised(model, MIN_STEP)
    assert "must be >=" not in at.error, at.error
