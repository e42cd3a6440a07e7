"""The scenes' descriptions (what ``parcosim scenes`` and the reports print) read back word for
word against what each scene was built with (issue 31: text never read back): the bench scene
(kind, strategy, model), the bench twin (kind, strategy, the delay and PWM it adds, the seed
and every twin value to four digits) and the vertical circle (counter-masses, frequency,
strategy, model)."""
from __future__ import annotations

from scenarios.scenes.thesis import VERTICAL_COUNTER_MASSES, bench, vertical_circle
from scenarios.scenes.twin import DELAY_STEPS, PWM_COUNTS, Twin, bench_real


def test_the_bench_scene_says_its_kind_strategy_and_model():
    """Catches the kind, the strategy or the model of another argument (or the default's)."""
    assert bench("PDMDx", "triangle", "seed").description == (
        "Bench of 7.2, triangle trajectory, strategy PDMDx (Tables 6-8), seed model")


def test_the_twin_scene_says_its_effects_seed_and_every_value():
    """A twin with every value away from its default and seed 7: the description names the
    kind, the strategy, the 1-sample delay, the 960-step PWM, seed 7 and each value as
    ``name value`` to 4 significant digits, in the twin's order.  Catches the description of the
    bench scene underneath kept, the seed's default shown, a value of another parameter."""
    twin = Twin(friction_scale=2.0, stiction_ratio=1.5, stribeck_speed=0.123456, current_offset=0.05,
                current_noise=0.03, inertia_error=0.25)
    scene = bench_real("TCMDx", "triangle", twin, seed=7)
    values = ", ".join(f"{k} {v:.4g}" for k, v in twin.values().items())
    assert "stribeck_speed 0.1235" in values and "inertia_error 0.25" in values
    assert scene.description == (f"Bench twin (docs/twin.md), triangle trajectory, strategy TCMDx: the bench scene with "
                                 f"a {DELAY_STEPS}-sample delay, {PWM_COUNTS}-step PWM, LuGre friction, noise and "
                                 f"encoder-phase seed 7; {values}")
    assert (DELAY_STEPS, PWM_COUNTS) == (1, 960)


def test_the_vertical_circle_says_its_counter_masses_frequency_strategy_and_model():
    """Balanced at 0.5 Hz with the seed model, and plain at the scenes' 1 Hz: each description
    names what it was built with.  Catches the bench scene's description kept, the two
    counter-masses swapped, the balanced and plain texts crossed."""
    heavy = vertical_circle("TCx", True, "seed", frequency=0.5)
    proximal, distal = VERTICAL_COUNTER_MASSES
    assert heavy.name == "vertical_circle_balanced_TCx"
    assert heavy.description == (
        "Bench of 7.2 in a vertical plane (gravity -9.81 m/s² along -y), "
        f"counter-masses {proximal:g} kg (proximal) and {distal:g} kg (distal) on each chain, "
        "circle (7.23) at 0.5 Hz, strategy TCx, seed model with the same gravity and masses")
    plain = vertical_circle("PDq", False)
    assert plain.name == "vertical_circle_PDq"
    assert plain.description == (
        "Bench of 7.2 in a vertical plane (gravity -9.81 m/s² along -y), no counter-masses, "
        "circle (7.23) at 1 Hz, strategy PDq, tabulated model with the same gravity and masses")
