"""The plant's encoders with zero errors (``encoder_offsets``, ``encoder_offset1/2``: 0 by
default, so a test at the default cannot tell ``q + offset`` from ``q`` or ``q - offset``), at
a 2 ms step: the readings against the docstring's rule (q + offset rounded to whole counts)
computed here, through the simulator, the FiveBarPlant FMU's slave and the model correction
that reads them (issue 31, patterns 1 and 2)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fmus.cosim.backends import InProcessInstance
from plant import PlantSimulator, fivebar, get_preset
from plant.correction import CELL_MARGIN, VELOCITY_GAIN, corrected_state

H = 2e-3
COUNT = 2.0 * math.pi / 20000
#: Zero errors of 2.37 and -4.61 counts: not whole counts, of both signs.
OFFSETS = (2.37 * COUNT, -4.61 * COUNT)


def _reading(q, offset):
    """q + offset to the nearest count (halves up): the encoder's rule, written here."""
    return COUNT * math.floor((q + offset) / COUNT + 0.5)


def _pushed(offsets, steps=150):
    sim = PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108, encoder_offsets=offsets)
    for _ in range(steps):
        sim.step(0.02, -0.01, H)
    return sim


@pytest.fixture(scope="module")
def pair():
    return _pushed((0.0, 0.0)), _pushed(OFFSETS)


def test_an_encoder_offset_shifts_the_reading_and_nothing_else(pair):
    """The same motion with and without zero errors (the offsets change no dynamics: the state
    is the same to the bit); each reading is q + offset to whole counts.  Catches the offset
    added to the wrong encoder, subtracted, applied to q itself, or dropped."""
    plain, shifted = pair
    assert np.array_equal(plain.y, shifted.y)
    o, s = plain.outputs(), shifted.outputs()
    assert o["q1"] == s["q1"] and abs(o["q1"]) > 0.1
    for k, offset in ((1, OFFSETS[0]), (2, OFFSETS[1])):
        assert s[f"q{k}_enc"] == pytest.approx(_reading(s[f"q{k}"], offset), abs=1e-15)
        assert o[f"q{k}_enc"] == pytest.approx(_reading(o[f"q{k}"], 0.0), abs=1e-15)
    assert round((s["q1_enc"] - o["q1_enc"]) / COUNT) in (2, 3)
    assert round((s["q2_enc"] - o["q2_enc"]) / COUNT) in (-5, -4)


def test_the_readings_before_the_first_step_and_after_a_state_is_set_have_the_offsets(pair):
    """The outputs computed in Python (no kernel report yet: at the start, and after the state
    is set from outside, as a restored FMU state does) follow the same rule as the stepped
    ones.  Catches the Python reading's offset dropped or of the wrong sign (the compiled
    step's readings are another code path)."""
    fresh = PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108, encoder_offsets=OFFSETS)
    o = fresh.outputs()
    for k, offset in ((1, OFFSETS[0]), (2, OFFSETS[1])):
        assert o[f"q{k}_enc"] == pytest.approx(_reading(o[f"q{k}"], offset), abs=1e-15)
        assert abs(o[f"q{k}_enc"] - _reading(o[f"q{k}"], 0.0)) > 1.5 * COUNT
    fresh.y = pair[1].y.copy()
    assert fresh.outputs() == pytest.approx(pair[1].outputs(), abs=1e-15)


@pytest.mark.parametrize("offsets", [(math.inf, 0.0), (0.0, math.nan), (0.0,), (0.0, 0.0, 0.0)])
def test_offsets_that_are_not_two_finite_numbers_are_refused(offsets):
    """Catches the check's ``len != 2`` or ``isfinite`` dropped."""
    with pytest.raises(ValueError, match=r"encoder_offsets must be 2 finite numbers \[rad\]"):
        PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108, encoder_offsets=offsets)


def test_the_fivebarplant_fmu_reads_its_encoders_with_its_offset_parameters():
    """The FMU's ``encoder_offset1/2`` parameters reach the simulator's encoders (each to its
    own), stepped at 2 ms.  Catches the parameters passed swapped or not at all."""
    plant = InProcessInstance("FiveBarPlant", "plant")
    plant.initialize({"preset": "bench", "x0": -0.002, "y0": 0.108,
                      "encoder_offset1": OFFSETS[0], "encoder_offset2": OFFSETS[1]}, 0.0)
    slave = plant.slave
    slave.tau1, slave.tau2 = 0.02, -0.01
    for k in range(150):
        plant.do_step(k * H, H)
    assert slave.q1 == pytest.approx(_pushed((0.0, 0.0)).outputs()["q1"], abs=1e-12)
    assert slave.q1_enc == pytest.approx(_reading(slave.q1, OFFSETS[0]), abs=1e-15)
    assert slave.q2_enc == pytest.approx(_reading(slave.q2, OFFSETS[1]), abs=1e-15)


def test_a_correction_reads_the_encoders_through_their_offsets(pair):
    """corrected_state on the plant with zero errors: its own readings agree (nothing moves);
    a reading one count above moves the angle just inside that cell *less the offset*, and
    its speed by VELOCITY_GAIN times the move over the 2 ms step.  Catches the offset left
    out of the cell test or of the moved angle, or its sign turned."""
    _, sim = pair
    o = sim.outputs()
    assert corrected_state(sim, {"q1_enc": o["q1_enc"], "q2_enc": o["q2_enc"]}, H) is None
    reading = o["q1_enc"] + COUNT
    z = corrected_state(sim, {"q1_enc": reading, "q2_enc": o["q2_enc"]}, H)
    q1, q2 = fivebar.world_angles(z[:7])
    assert q1 == pytest.approx(reading - (0.5 - CELL_MARGIN) * COUNT - OFFSETS[0], abs=1e-13)
    assert _reading(q1, OFFSETS[0]) == pytest.approx(reading, abs=1e-15)
    assert q2 == pytest.approx(o["q2"], abs=1e-13)
    dq1, dq2 = fivebar.world_rates(z[7:])
    assert dq1 == pytest.approx(o["dq1"] + VELOCITY_GAIN * (q1 - o["q1"]) / H, rel=1e-9)
    assert dq2 == pytest.approx(o["dq2"], abs=1e-9)
