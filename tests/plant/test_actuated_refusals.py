"""ActuatedPlant.kernel_refusal (plant/actuated.py): the refusal of a compiled actuated step for
each status the kernel returns, read back (reason, variable, value, message) against the texts
of the plant's own checks: a non-finite plant state names its state word, a non-finite current
the drive's current, a diverged or singular step the plant's measure; the state is kept."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from motor import Drive, get_motor_preset
from plant import PlantError, PlantSimulator, fast5r, get_preset
from plant.actuated import ActuatedPlant

START = (-0.002, 0.108)
DT = 1e-3


def actuated():
    sim = PlantSimulator(get_preset("bench"), *START)
    return ActuatedPlant(sim, [(j, Drive(get_motor_preset(f"motor{j}"))) for j in (1, 2)])


@pytest.mark.parametrize("status, index, value, variable, words", [
    (fast5r.NONFINITE_STATE, 5, math.nan, "state[5]", "state became non-finite in the step from t = 0 s ("),
    (fast5r.NONFINITE_STATE, 13, math.inf, "state[13]", "state became non-finite in the step from t = 0 s ("),
    (fast5r.NONFINITE_STATE, 14, math.nan, "i1", "armature currents [nan, 0.0] after the step from t = 0 s ("),
    (fast5r.NONFINITE_STATE, 15, math.inf, "i2", "armature currents [0.0, inf] after the step from t = 0 s ("),
    (fast5r.DIVERGED, 0, 2.5e-3, "residual", "loop-closure residual 0.0025 m"),
    (fast5r.SINGULAR, 2, 1e-9, "distal links (parallel)", "t = 0.001 s"),
])
def test_each_kernel_status_is_the_plants_refusal_naming_its_word(status, index, value, variable, words):
    """Catches a refusal that takes a plant state word for a current (or the other way round),
    names another word, value or status, or changes the state."""
    a = actuated()
    state = a.state()
    trial = state.copy()
    trial[index] = value if index >= fast5r.PLANT_STATES or status == fast5r.NONFINITE_STATE else trial[index]
    refusal = kernels.Refusal(code=status, index=index, value=value)
    exc = a.kernel_refusal(status, refusal, trial, (0.5, -0.5), (0.0, 0.0), (0.0, 0.0), DT)
    assert isinstance(exc, PlantError)
    record = exc.record()
    assert record["variable"] == variable, record
    assert record["value"] == value or math.isnan(value) and math.isnan(record["value"])
    assert words in str(exc), str(exc)
    assert ("V held" in str(exc)) == (status != fast5r.SINGULAR), str(exc)      # the voltages a step held
    assert np.array_equal(a.state(), state)
