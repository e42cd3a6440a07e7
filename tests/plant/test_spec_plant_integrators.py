"""A spec-built plant's integrators (plant/specsim.py ``SpecSimulator.step``): dopri5 and RK4
against FiveBarPlant's general kernel with the same settings, and the evaluations each step
returns against the right-hand-side calls counted here."""
from __future__ import annotations

import math

import numpy as np
import pytest

from plant import IntegratorSettings, PlantSimulator, get_preset
from plant import spec as plant_spec
from plant.specsim import SpecSimulator

START = (0.07, 0.17)
STEPS = 20


def _torques(t):
    return 0.02 * math.sin(2 * math.pi * t) + 0.01, -0.015 * math.cos(3 * math.pi * t)


@pytest.mark.parametrize("settings", [IntegratorSettings(kernel="general", method="dopri5", rtol=1e-9, atol=1e-12),
                                      IntegratorSettings(kernel="general", substeps=3)], ids=["dopri5", "rk4-3"])
def test_each_integrator_is_five_bar_plants_and_returns_its_calls(settings):
    """20 steps of 1 ms under the docs' torque profile: the spec plant's (x, y) equal
    FiveBarPlant's general kernel integrated with the same settings (1e-9 m), and each step
    returns the derivative calls it made (RK4: 4 per substep).  Catches dopri5 given its
    tolerances shifted or dropped, a count that is not the calls, and settings not used."""
    spec_sim = SpecSimulator(plant_spec.load("thesis_sim_5r"), (*START, 0.0), settings)
    plant = PlantSimulator(get_preset("thesis_sim"), *START, settings)
    calls, derivative = [], spec_sim.derivative
    spec_sim.derivative = lambda z, u: calls.append(1) or derivative(z, u)
    returned = []
    for i in range(STEPS):
        returned.append(spec_sim.step(np.array(_torques(i * 1e-3)), 1e-3))
        plant.step(*_torques(i * 1e-3), 1e-3)
        a, b = spec_sim.outputs(), plant.outputs()
        assert math.hypot(a["x"] - b["x"], a["y"] - b["y"]) <= 1e-9, i
    assert sum(returned) == len(calls)
    if settings.method == "rk4":
        assert returned == [12] * STEPS
    else:
        assert min(returned) >= 6       # one dopri5 step: at least 6 stages
    assert math.hypot(a["x"] - START[0], a["y"] - START[1]) > 1e-5          # it moved
