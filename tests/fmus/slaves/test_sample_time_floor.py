"""Each sampled slave refuses a sample time below the shortest step (MIN_STEP = 1 ns) at
initialisation, naming T and the bound (seed 3501's survivor [50], fmus/slaves/
parcosim_dcmotordrive.py:73: the drive's ``0.0 < T`` -> ``1.0 < T`` passed every test)."""
from __future__ import annotations

import pytest

from fmus.cosim.backends import InProcessInstance
from fmus.slave.base import MIN_STEP

EXTRA = {"ActuatedFiveBarPlant": {"preset": "bench", "x0": -0.002, "y0": 0.108}, "PositionController": {"model": "exact"}}


@pytest.mark.parametrize("model", ["DCMotorDrive", "ActuatedFiveBarPlant", "CurrentObserver", "PositionController",
                                   "BalanceController", "Derivator"])
def test_a_sample_time_below_the_shortest_step_is_refused_naming_it(model):
    """Catches a sample time below the shortest step a master may take accepted (each call then runs
    millions of samples) or refused without naming T."""
    instance = InProcessInstance(model, "x")
    instance.initialize({"T": MIN_STEP / 2, **EXTRA.get(model, {})}, 0.0)
    error = instance.slave.error
    assert error.startswith("initialisation refused: parameter T = 5e-10 s ")
    assert "must be >= 1e-09 s" in error or "is below the shortest step 1e-09 s" in error
