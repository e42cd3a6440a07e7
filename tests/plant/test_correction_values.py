"""plant.correction's numbers as documented, not as imported: the speed gain 0.3 of
docs/ssp.md ("its speed by 0.3 of the move per step"), a corrected angle 0.05 of a count
inside its cell's edge, and the 1e-10 tolerance under which an exact measurement leaves the
model alone, hit on both sides.  Catches a changed constant that the tests reading the
constants themselves would follow."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

from plant import PlantSimulator, fivebar, get_preset
from plant.correction import corrected_state

H = 2e-3
DOCS = Path(__file__).resolve().parents[2] / "docs"


@pytest.fixture(scope="module")
def moving():
    sim = PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108)
    for _ in range(100):
        sim.step(0.02, -0.01, 1e-3)
    return sim


def test_the_speed_gain_used_here_is_the_one_docs_ssp_gives():
    assert "its speed by 0.3 of the move per" in (DOCS / "ssp.md").read_text()


@pytest.mark.parametrize("off", [1, -2])
def test_the_documented_cell_margin_and_speed_gain(moving, off):
    o, c = moving.outputs(), moving.count
    z = corrected_state(moving, {"q1_enc": o["q1_enc"], "q2_enc": o["q2_enc"] + off * c}, H)
    q1, q2 = fivebar.world_angles(z[:7])
    near_edge = o["q2_enc"] + off * c - math.copysign(0.5, off) * c
    assert q2 == pytest.approx(near_edge + math.copysign(0.05, off) * c, abs=1e-13)
    dq1, dq2 = fivebar.world_rates(z[7:])
    assert dq2 == pytest.approx(o["dq2"] + 0.3 * (q2 - o["q2"]) / H, rel=1e-9)
    assert q1 == pytest.approx(o["q1"], abs=1e-13) and dq1 == pytest.approx(o["dq1"], abs=1e-9)


@pytest.mark.parametrize("name", ["q1", "q2", "dq1", "dq2"])
def test_an_exact_measurement_within_1e_10_is_ignored_and_beyond_it_taken(moving, name):
    o = moving.outputs()
    assert corrected_state(moving, {name: o[name] + 0.9e-10}, H) is None
    z = corrected_state(moving, {name: o[name] - 1.2e-10}, H)
    assert z is not None
    got = dict(zip(("q1", "q2"), fivebar.world_angles(z[:7])))
    got.update(zip(("dq1", "dq2"), fivebar.world_rates(z[7:])))
    assert got[name] == pytest.approx(o[name] - 1.2e-10, abs=1e-14)
