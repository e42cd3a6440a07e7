"""PlantSimulator.step's refusal of a torque that is not finite (plant/simulator.py), on every
integration path: the one C call (RK4, fast kernel, no projection) at a new step length and at
a step length already accepted (the kernel's own refusal), the C kernel with projection, the
general kernel and dopri5.  Each refusal is read back whole: the message word for word, the
record (reason, variable, value, unit, code, time), and nothing stepped."""
from __future__ import annotations

import math

import numpy as np
import pytest

from plant import IntegratorSettings, PlantError, PlantSimulator, fast5r, get_preset

SETTINGS = {"one call": IntegratorSettings(), "projection": IntegratorSettings(project=True),
            "general": IntegratorSettings(kernel="general"), "dopri5": IntegratorSettings(method="dopri5")}
DT = 1e-3


@pytest.mark.parametrize("path", sorted(SETTINGS))
@pytest.mark.parametrize("tau1, tau2, name, value", [
    (math.nan, 0.015, "tau1", math.nan), (-0.02, math.inf, "tau2", math.inf),
    (-math.inf, 0.015, "tau1", -math.inf), (math.nan, math.nan, "tau1", math.nan),   # both: tau1 first
])
def test_a_non_finite_torque_is_refused_by_name_value_and_time_on_every_path(path, tau1, tau2, name, value):
    """Catches a step whose torque check looks at another quantity (the step length for tau1,
    tau1 twice) on one of the paths, so that a NaN torque is integrated (or refused later as a
    divergence) instead of being named; a record naming another variable, value, time or
    reason; a refused step that moves the state or the clock."""
    sim = PlantSimulator(get_preset("bench"), -0.002, 0.108, SETTINGS[path])
    for t in (0.0, DT):               # at t = 0 the first step; at t = 1 ms a step length already taken
        state = sim.y.copy()
        with pytest.raises(PlantError) as caught:
            sim.step(tau1, tau2, DT)
        words = f"{value!r}" if not math.isnan(value) else "nan"
        assert str(caught.value) == f"input {name} = {words} at t = {t:.6g} s is not finite"
        record = caught.value.record()
        assert (record["reason"], record["variable"], record["unit"], record["code"], record["time"]) == \
            ("nonfinite_input", name, "N m", fast5r.NONFINITE_INPUT, t)
        assert record["value"] == value or math.isnan(value) and math.isnan(record["value"])
        assert caught.value.names_time
        assert np.array_equal(sim.y, state) and sim.time == t
        sim.step(0.01, -0.02, DT)                                       # finite torques: stepped
        assert sim.time == t + DT and not np.array_equal(sim.y, state)
