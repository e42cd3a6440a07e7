"""The plant's documented limits (docs/plant.md "Refusals added by the extremes suite",
thesis Table 5) at their edges: substeps up to 10000, RK4's baumgarte * h / substeps up to 2,
a diverged residual above 1e-3 m, 20000 encoder counts (5000 pulses in quadrature)."""
import re
from dataclasses import replace
from pathlib import Path

import pytest

from plant import IntegratorSettings, PlantError, PlantSimulator, get_preset
from plant import simulator

START = (-0.002, 0.108)
DOC = " ".join((Path(__file__).resolve().parents[2] / "docs" / "plant.md").read_text().split())


def test_the_documented_limits_are_the_plants():
    assert "`substeps` is at most 10000" in DOC and simulator.MAX_SUBSTEPS == 10000
    assert re.search(r"loop-closure residual \(5\.18\) exceeds 1e-3 m is refused", DOC)
    assert simulator.RESIDUAL_STOP == 1e-3
    assert "RK4 with `baumgarte * h / substeps` above 2 is refused" in DOC and simulator.BAUMGARTE_RK4_LIMIT == 2.0
    assert simulator.ENCODER_COUNTS == 4 * 5000


@pytest.mark.parametrize("substeps", [0, -1, 10001, 2.0])
def test_substeps_outside_1_to_10000_or_not_an_integer_are_refused_word_for_word(substeps):
    with pytest.raises(ValueError) as info:
        IntegratorSettings(substeps=substeps).validate()
    assert str(info.value) == f"substeps must be an integer in [1, 10000], got {substeps!r}"


def test_substeps_of_1_and_10000_are_accepted():
    assert IntegratorSettings(substeps=1).validate().substeps == 1
    assert IntegratorSettings(substeps=10000).validate().substeps == 10000


def test_rk4_baumgarte_h_of_exactly_2_is_stepped_and_just_above_refused():
    """2000 /s at 1 ms in one RK4 step: baumgarte h = 2, accepted; 2000.5 /s refused before stepping."""
    ok = PlantSimulator(get_preset("bench"), *START, IntegratorSettings(substeps=1, baumgarte=2000.0))
    assert 2000.0 * 1e-3 / 1 == 2.0
    ok.step(0.0, 0.0, 1e-3)
    assert ok.time == 1e-3
    refused = PlantSimulator(get_preset("bench"), *START, IntegratorSettings(substeps=1, baumgarte=2000.5))
    with pytest.raises(PlantError, match=r"baumgarte = 2000.5 /s with RK4 steps of 0.001 s"):
        refused.step(0.0, 0.0, 1e-3)
    assert refused.time == 0.0


def _spec_plant(settings):
    from plant import spec as plant_spec
    from plant.specsim import SpecSimulator

    return SpecSimulator(plant_spec.load("bench_5r"), (0.07, 0.17, 0.0), settings=settings)


@pytest.mark.parametrize("kind", ["5r", "spec"])
def test_the_rk4_baumgarte_limit_is_on_the_substep_not_the_communication_step(kind):
    """4000 /s at 1 ms in 2 RK4 sub-steps: baumgarte h = 4000 * 0.5 ms = 2, stepped (over the
    whole 1 ms it would be 4); 4000.5 /s refused before stepping, naming the sub-step; dopri5
    (no fixed step) takes 4000.5 /s.  For the 5R plant and a spec plant alike.  Catches a
    limit that forgets the sub-steps or holds dopri5 to RK4's."""
    def plant(baumgarte, method="rk4"):
        settings = IntegratorSettings(method=method, substeps=2, baumgarte=baumgarte)
        if kind == "5r":
            sim = PlantSimulator(get_preset("bench"), *START, settings)
            return sim, lambda: sim.step(0.0, 0.0, 1e-3)
        sim = _spec_plant(replace(settings, kernel="general", project=False))
        return sim, lambda: sim.step((0.0, 0.0), 1e-3)

    assert 4000.0 * 1e-3 / 2 == 2.0
    ok, step = plant(4000.0)
    step()
    assert ok.time == 1e-3
    refused, step = plant(4000.5)
    with pytest.raises(PlantError, match=r"baumgarte = 4000.5 /s with RK4 steps of 0.0005 s"):
        step()
    assert refused.time == 0.0
    adaptive, step = plant(4000.5, "dopri5")
    step()
    assert adaptive.time == 1e-3
