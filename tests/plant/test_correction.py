"""plant.correction: the model of the plant moved to what was measured of the real one."""
from __future__ import annotations

import math

import numpy as np
import pytest

from plant import PlantSimulator, fivebar, get_preset
from plant.correction import CELL_MARGIN, VELOCITY_GAIN, consistent_state, corrected_state

H = 1e-3


@pytest.fixture(scope="module")
def moving():
    """The bench 5R 0.3 s into a push: moving, off every symmetric pose."""
    sim = PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108)
    for _ in range(300):
        sim.step(0.02, -0.01, H)
    return sim


def test_consistent_state_closes_the_loop_at_the_given_angles_and_speeds(moving):
    """Catches a corrected state off the given angles or speeds, or with its loop open."""
    o = moving.outputs()
    z = consistent_state(moving, [o["q1"] + 0.01, o["q2"] - 0.02], [0.3, -0.4])
    assert fivebar.world_angles(z[:7]) == pytest.approx((o["q1"] + 0.01, o["q2"] - 0.02), abs=1e-14)
    assert fivebar.world_rates(z[7:]) == pytest.approx((0.3, -0.4), abs=1e-12)
    assert moving._residual_of(z) < 1e-14
    # the same angles and speeds give back the integrated state (to its loop residual)
    again = consistent_state(moving, [o["q1"], o["q2"]], [o["dq1"], o["dq2"]])
    assert np.max(np.abs(again - moving.y)) < 1e-9


def test_agreeing_measurements_change_nothing(moving):
    """Catches a correction that moves the model when the measurements already agree with it."""
    o = moving.outputs()
    assert corrected_state(moving, {k: o[k] for k in ("q1_enc", "q2_enc")}, H) is None
    assert corrected_state(moving, {k: o[k] for k in ("q1", "q2", "dq1", "dq2")}, H) is None


@pytest.mark.parametrize("off", [1, -1], ids=["above", "below"])
def test_a_reading_one_count_off_moves_the_angle_just_inside_its_cell(moving, off):
    """The model's angle moves to the near edge of the measured cell (a margin inside), on
    whichever side of it the angle lies: the least move the reading allows."""
    o, c = moving.outputs(), moving.count
    z = corrected_state(moving, {"q1_enc": o["q1_enc"] + off * c, "q2_enc": o["q2_enc"]}, H)
    q1, q2 = fivebar.world_angles(z[:7])
    assert math.floor(q1 / c + 0.5) * c == pytest.approx(o["q1_enc"] + off * c, abs=1e-15)
    assert q1 == pytest.approx(o["q1_enc"] + off * c - off * (0.5 - CELL_MARGIN) * c, abs=1e-13)
    assert q2 == pytest.approx(o["q2"], abs=1e-13)          # inside its cell: left alone
    dq1, dq2 = fivebar.world_rates(z[7:])
    assert dq1 == pytest.approx(o["dq1"] + VELOCITY_GAIN * (q1 - o["q1"]) / H, rel=1e-9)
    assert dq2 == pytest.approx(o["dq2"], abs=1e-9)


def test_exact_measurements_are_taken_as_they_are(moving):
    """Catches a correction that rounds or filters an exact (not encoder) measurement."""
    o = moving.outputs()
    z = corrected_state(moving, {"q1": o["q1"] + 1e-4, "q2": o["q2"], "dq1": 0.5, "dq2": o["dq2"]}, H)
    assert fivebar.world_angles(z[:7]) == pytest.approx((o["q1"] + 1e-4, o["q2"]), abs=1e-14)
    assert fivebar.world_rates(z[7:])[0] == pytest.approx(0.5, abs=1e-12)


def test_unmeasurable_outputs_are_refused(moving):
    """Catches a correction that silently ignores an output it cannot correct the model with."""
    with pytest.raises(ValueError, match="cannot correct the plant model with \\['x'\\]"):
        corrected_state(moving, {"x": 0.0}, H)


def test_an_exact_measurement_an_ulp_away_changes_nothing(moving):
    """A master whose step sizes are an ulp off the model's (libcosim) must not make the
    model correct itself every step; a real difference still does."""
    o = moving.outputs()
    nudged = {k: float(np.nextafter(o[k], np.inf)) for k in ("q1", "q2", "dq1", "dq2")}
    assert corrected_state(moving, nudged, H) is None
    assert corrected_state(moving, {**nudged, "dq2": o["dq2"] + 1e-6}, H) is not None
