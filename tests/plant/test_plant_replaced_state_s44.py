"""A FiveBarPlant whose state is replaced from outside after a kernel step (an FMU state
restored) publishes the new state's outputs, not the last step's report (plant/simulator.py:
``outputs``, ``output_values`` and ``residual_norm`` read the report only while it is of the
present ``y``).  Session 44, training sample 4421 [8]: the cache test of ``residual_norm`` turned
round."""
from __future__ import annotations

import math

import numpy as np
import pytest

from plant import PlantSimulator, fivebar, get_preset
from plant.parallel import mechanism_state


def test_every_output_after_the_state_is_replaced_is_the_new_states():
    """Step a moving plant, then set ``y`` to another plant's state (another pose, off the
    constraints by 1e-4 rad): each output is the new state's (world angles and rates, tip,
    encoders of the new angles, residual by the general model), in outputs(), output_values()
    and residual_norm() alike."""
    bench = get_preset("bench")
    sim = PlantSimulator(bench, 0.0, 0.15, dx0=0.3, dy0=-0.2)
    for _ in range(3):
        sim.step(0.02, -0.01, 1e-3)
    stepped = sim.outputs()
    other = PlantSimulator(bench, 0.03, 0.18, dx0=-0.1, dy0=0.25).y.copy()
    other[3:7] += (1e-4, -2e-4, 1e-4, 3e-4)
    sim.y = other
    q1, q2 = fivebar.world_angles(other[:7])
    dq1, dq2 = fivebar.world_rates(other[7:])
    residual = float(np.linalg.norm(mechanism_state(sim.mechanism, other[:7], other[7:]).residual))
    count = sim.count
    expected = {"q1": q1, "q2": q2, "dq1": dq1, "dq2": dq2, "x": other[0], "y": other[1], "dx": other[7],
                "dy": other[8], "q1_enc": count * math.floor(q1 / count + 0.5),
                "q2_enc": count * math.floor(q2 / count + 0.5), "residual": residual}
    assert residual > 1e-5 and abs(stepped["x"] - other[0]) > 0.01
    out = sim.outputs()
    for name, value in expected.items():
        assert out[name] == pytest.approx(value, rel=1e-9, abs=1e-15), name
    assert sim.output_values() == pytest.approx(list(expected.values()), rel=1e-9, abs=1e-15)
    assert sim.residual_norm() == pytest.approx(residual, rel=1e-9)
