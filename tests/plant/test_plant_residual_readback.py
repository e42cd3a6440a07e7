"""``PlantSimulator.residual_norm`` and the ``residual`` output of a state set from outside
(an FMU state restored, a test's perturbation): the loop-closure residual (5.18) of that
state, computed here with the general model, not the one the last step left."""
import numpy as np
import pytest

from plant import IntegratorSettings, PlantSimulator, get_preset
from plant.parallel import mechanism_state


@pytest.mark.parametrize("kernel", ["fast", "general"])
def test_the_residual_is_that_of_the_present_state_after_it_is_replaced(kernel):
    sim = PlantSimulator(get_preset("bench"), -0.002, 0.108, IntegratorSettings(kernel=kernel))
    sim.step(0.01, -0.01, 1e-3)
    stepped = sim.residual_norm()
    y = sim.y.copy()
    y[3:7] += (1e-4, -2e-4, 3e-4, 1e-4)       # off the constraints
    sim.y = y
    expected = float(np.linalg.norm(mechanism_state(sim.mechanism, y[:7], y[7:]).residual))
    assert expected > 1e-5 > stepped
    assert sim.residual_norm() == pytest.approx(expected, rel=1e-9)
    assert sim.outputs()["residual"] == pytest.approx(expected, rel=1e-9)
