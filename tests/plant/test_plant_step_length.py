"""The plants at a 2 ms step: one step of 2 ms with n RK4 sub-steps is two steps of 1 ms with
n/2 (the same 2 ms / n sub-step, the same torques held), for the 5R (both kernels), the
wheeled pendulum and the pendulum's disturbance torque (issue 31, pattern 1: a sub-step taken
from the default 1 ms, or the step's length lost, shows here and nowhere at 1 ms)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from plant import IntegratorSettings, PlantSimulator, get_preset
from plant.wheeled import WheeledPendulum


@pytest.mark.parametrize("kernel", ["fast", "general"])
def test_one_2ms_step_is_two_1ms_steps_of_the_same_sub_step(kernel):
    """Torques held over each pair of 1 ms steps as over the 2 ms step; 50 ms.  Catches a
    sub-step of dt / substeps replaced by a constant, the time not advanced by dt."""
    long = PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108,
                          settings=IntegratorSettings(substeps=4, kernel=kernel))
    short = PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108,
                           settings=IntegratorSettings(substeps=2, kernel=kernel))
    for k in range(25):
        tau = (0.03 * math.sin(0.3 * k), -0.02 + 0.01 * math.cos(0.2 * k))
        long.step(*tau, 2e-3)
        short.step(*tau, 1e-3)
        short.step(*tau, 1e-3)
    assert long.time == pytest.approx(0.05, abs=1e-15) and short.time == pytest.approx(0.05, abs=1e-15)
    moved = np.abs(long.y - PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108).y).max()
    assert moved > 1e-4
    assert np.max(np.abs(long.y - short.y)) < 1e-12 * max(1.0, moved)


def test_the_wheeled_pendulum_at_2ms_is_two_1ms_steps_with_the_disturbance():
    """With a disturbance torque on the body (0 by default): catches tau_d not held over the
    whole step, or the sub-step length taken from the default."""
    long = WheeledPendulum(initial={"psi": 0.05}, substeps=4)
    short = WheeledPendulum(initial={"psi": 0.05}, substeps=2)
    still = WheeledPendulum(initial={"psi": 0.05}, substeps=4)
    for k in range(25):
        tau = (0.02 * math.sin(0.3 * k), -0.01)
        long.step(*tau, 2e-3, tau_d=0.05)
        short.step(*tau, 1e-3, tau_d=0.05)
        short.step(*tau, 1e-3, tau_d=0.05)
        still.step(*tau, 2e-3)
    assert long.time == pytest.approx(0.05, abs=1e-15)
    assert np.max(np.abs(long.y - short.y)) < 1e-12
    assert np.max(np.abs(long.y - still.y)) > 1e-5                 # the disturbance acts


@pytest.mark.parametrize("dt", [-1e-3, 0.0, math.inf, math.nan])
def test_a_step_that_is_not_finite_and_positive_is_refused_naming_it_and_nothing_moves(dt):
    """Seed 3501's survivor [44] (plant/simulator.py:305, ``isfinite(dt) and dt > 0`` -> ``or``):
    a negative or infinite step is refused by the simulator's own check, with its message,
    before the kernel sees it, and the state and time stay."""
    from plant.simulator import PlantError

    sim = PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108)
    sim.step(0.01, 0.0, 2e-3)
    y, t = sim.y.copy(), sim.time
    with pytest.raises(PlantError, match=rf"^step size {dt!r} at t = 0.002 s must be > 0$"):
        sim.step(0.01, 0.0, dt)
    assert np.array_equal(sim.y, y) and sim.time == t
