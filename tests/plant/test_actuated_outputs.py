"""The outputs of a compiled actuated step (``ActuatedPlant._step_in_c``, one C call for the
plant and both drives) against the same quantities computed in Python from the state it
leaves: angles, rates, the platform, the encoders and the loop-closure residual (5.18) of the
general model."""
from __future__ import annotations

import math

import numpy as np
import pytest

from motor import Drive, get_motor_preset
from plant import PlantSimulator, fivebar, get_preset
from plant.actuated import ActuatedPlant
from plant.parallel import mechanism_state

START = (-0.002, 0.108)
DT = 1e-3


def test_a_compiled_actuated_steps_outputs_are_those_of_the_state_it_leaves():
    sim = PlantSimulator(get_preset("bench"), *START, encoder_offsets=(2.37e-3, -4.61e-3))
    a = ActuatedPlant(sim, [(j, Drive(get_motor_preset(f"motor{j}"))) for j in (1, 2)])
    assert a._one_call    # the compiled path is the one under test
    for _ in range(3):
        a.step((0.4, -0.3), (0.0, 0.0), (0.0, 0.0), DT)
        y = sim.y
        out = sim.outputs()
        residual = float(np.linalg.norm(mechanism_state(sim.mechanism, y[:7], y[7:]).residual))
        assert out["residual"] == pytest.approx(residual, rel=1e-6, abs=1e-15)
        assert sim.residual_norm() == out["residual"]
        assert out["residual"] < 1e-6          # a closed loop, not some other output
        q1, q2 = fivebar.world_angles(y[:7].tolist())
        dq1, dq2 = fivebar.world_rates(y[7:].tolist())
        assert (out["q1"], out["q2"], out["dq1"], out["dq2"]) == pytest.approx((q1, q2, dq1, dq2), rel=1e-14, abs=1e-15)
        assert (out["x"], out["y"], out["dx"], out["dy"]) == (y[0], y[1], y[7], y[8])
        for name, q, offset in (("q1_enc", q1, 2.37e-3), ("q2_enc", q2, -4.61e-3)):
            assert out[name] == pytest.approx(sim.count * math.floor((q + offset) / sim.count + 0.5), abs=1e-15)
