"""scenarios/scenes/perturb.py without running anything (the sweeps' tests, which run scenes on
dask, are of the slow kind): which parameters a scene has, their nominal values from the
presets or the scene, their weights, the draws against the module docstring's formula with
the stream computed here, the LuGre break-away that follows its Coulomb torque, and the
perturbed scene compared whole (issue 31: zero-by-default parameters given non-zero values,
values compared exactly with an independent computation)."""
from __future__ import annotations

import math
import zlib
from dataclasses import replace

import numpy as np
import pytest

from motor import get_motor_preset
from plant import get_preset
from scenarios.scenes import get_scene
from scenarios.scenes.perturb import (ENCODER_OFFSET_SCALE, LENGTH_WEIGHT, TRUNCATE_SIGMA, draw,
                                      load_perturb_file, perturbable, perturbed, uncertainties)

CHAIN = ("l1", "l2", "lg1", "lg2", "m1", "m2", "Jz1", "Jz2")
MOTOR = ("R", "L", "kt", "ke", "b", "mu")


def _scene(plant=None, drive1=None, drive2=None):
    """bench_circle_TCMDx with parameters set on its plant and drives."""
    scene = get_scene("bench_circle_TCMDx")
    extra = {"plant": plant or {}, "drive1": drive1 or {}, "drive2": drive2 or {}}
    components = tuple(replace(c, parameters={**c.parameters, **extra[c.name]}) if c.name in extra else c
                       for c in scene.system.components)
    return replace(scene, system=replace(scene.system, components=components))


def _xi(seed, sample, name, distribution):
    """The docstring's stream: numpy SeedSequence(seed) spawned by (sample, crc32(name));
    uniform on [-1, 1], or the first standard normal within +-3."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(sample, zlib.crc32(name.encode()))))
    if distribution == "uniform":
        return rng.uniform(-1.0, 1.0)
    z = rng.standard_normal()
    while abs(z) > 3.0:
        z = rng.standard_normal()
    return z


def test_the_bench_scenes_parameters_are_the_presets_in_order_with_the_encoder_offsets():
    """Names, nominal values (Tables 4-5 and app. D through the presets), kinds and order.
    Catches a chain's field read from the other chain, a preset's field for another, the
    encoder offsets left out (their nominal is 0: only absolute parameters keep a 0), a
    motor of drive2 read from drive1's preset."""
    params = perturbable(_scene())
    bench, m1, m2 = get_preset("bench"), get_motor_preset("motor1"), get_motor_preset("motor2")
    expected = [("plant.l0", bench.l0, "length", False)]
    for k, chain in ((1, bench.chain1), (2, bench.chain2)):
        expected += [(f"plant.chain{k}_{f}", getattr(chain, f), "length" if f in ("l1", "l2") else "inertial", False)
                     for f in CHAIN]
        expected.append((f"plant.J_rotor{k}", chain.J_rotor, "inertial", False))
    expected += [("plant.encoder_offset1", 0.0, "encoder_offset", True),
                 ("plant.encoder_offset2", 0.0, "encoder_offset", True)]
    for name, motor in (("drive1", m1), ("drive2", m2)):
        expected += [(f"{name}.{f}", getattr(motor, f), "friction" if f in ("b", "mu") else "motor", False)
                     for f in MOTOR]
    assert [(p.name, p.nominal, p.kind, p.absolute) for p in params] == expected
    assert m1.R != m2.R and bench.chain1.l1 != bench.chain1.l2


def test_a_scenes_own_values_are_the_nominals_and_zero_ones_are_not_perturbed():
    """The scene's chain1_m1, R and a non-zero encoder offset are the nominal values; a rotor of
    inertia 0 and links without inertias drop out; a LuGre drive adds mu_s following mu.
    Catches ``_given`` reading the preset when the scene sets a value, the ``link_inertias``
    switch ignored, the offset's nominal taken as 0 when set."""
    scene = _scene(plant={"chain1_m1": 0.0777, "J_rotor2": 0.0, "link_inertias": False, "encoder_offset2": 2e-3},
                   drive2={"R": 1.75, "friction": "lugre"})
    params = {p.name: p for p in perturbable(scene)}
    assert params["plant.chain1_m1"].nominal == 0.0777 and params["drive2.R"].nominal == 1.75
    assert "plant.J_rotor2" not in params and params["plant.J_rotor1"].nominal == get_preset("bench").chain1.J_rotor
    assert not any("Jz" in name for name in params)
    assert params["plant.encoder_offset2"].nominal == 2e-3 and params["plant.encoder_offset1"].nominal == 0.0
    mu_s = params["drive2.mu_s"]
    assert (mu_s.nominal, mu_s.kind, mu_s.follows) == (get_motor_preset("motor2").mu_s, "friction", "drive2.mu")
    assert "drive1.mu_s" not in params


def test_weights_give_each_kind_its_uncertainty_and_the_last_matching_pattern_wins():
    """u_p = U * weight per kind (lengths 1 %, encoder offsets 0.01 rad per unit of U); a
    follower has none; the last of two matching patterns sets the value.  Catches a weight of
    the wrong kind, the order of the patterns reversed, a follower given U."""
    params = perturbable(_scene(drive1={"friction": "lugre"}))
    spread = uncertainties(params, 0.3)
    # the docstring's figures: U = 0.4 gives +-0.4 % on a length, +-4 mrad on an encoder's zero
    assert LENGTH_WEIGHT == 0.01 and ENCODER_OFFSET_SCALE == 0.01
    assert spread["plant.chain2_l1"] == 0.3 * 0.01 and spread["plant.l0"] == 0.3 * 0.01
    assert spread["plant.chain2_lg1"] == 0.3 and spread["drive2.ke"] == 0.3 and spread["drive1.b"] == 0.3
    assert spread["plant.encoder_offset2"] == 0.3 * 0.01
    zero = uncertainties(params, 0.0)                  # U = 0: the nominal run, accepted
    assert all(u == 0.0 for name, u in zero.items() if name != "drive1.mu_s")
    assert spread["drive1.mu_s"] is None
    spread = uncertainties(params, 0.3, {"drive*.R": 0.1, "drive2.*": 0.05, "drive1.mu_s": 0.2})
    assert spread["drive1.R"] == 0.1 and spread["drive2.R"] == 0.05 and spread["drive2.kt"] == 0.05
    assert spread["drive1.mu_s"] == 0.2 and spread["drive1.kt"] == 0.3


@pytest.mark.parametrize("U", [-0.1, math.inf, math.nan, "0.2"])
def test_an_uncertainty_that_is_not_a_finite_number_at_least_zero_is_refused(U):
    with pytest.raises(ValueError, match=rf"uncertainty U = {U!r} must be a finite number >= 0"):
        uncertainties(perturbable(_scene()), U)


@pytest.mark.parametrize("distribution", ["uniform", "normal"])
def test_draws_are_the_docstrings_formula_with_the_seeded_stream(distribution):
    """nominal (1 + u xi) for a relative parameter, nominal + u xi for an absolute one (an
    encoder offset of 2 mrad nominal), xi from the stream computed here; a parameter with
    u = 0 exactly nominal.  Catches a relative draw made absolute (or the reverse), the seed,
    sample or name left out of the stream, a truncation at another sigma."""
    scene = _scene(plant={"encoder_offset1": 2e-3})
    params = perturbable(scene)
    spread = uncertainties(params, 0.4, {"drive2.L": 0.0})
    values = draw(params, spread, 7, 5, distribution)
    for p in params:
        if p.name == "drive2.L":
            assert values[p.name] == p.nominal
            continue
        xi = _xi(7, 5, p.name, distribution)
        expected = p.nominal + spread[p.name] * xi if p.absolute else p.nominal * (1.0 + spread[p.name] * xi)
        assert values[p.name] == expected, p.name
    offset = values["plant.encoder_offset1"]
    assert offset != 2e-3 and abs(offset - 2e-3) <= 0.4 * ENCODER_OFFSET_SCALE * TRUNCATE_SIGMA
    other = draw(params, spread, 7, 6, distribution)
    assert all(other[n] != values[n] for n in values if n != "drive2.L")
    assert draw(params, spread, 8, 5, distribution)["drive1.R"] != values["drive1.R"]


def test_a_lugre_break_away_takes_its_coulomb_torques_relative_change_unless_drawn_itself():
    """mu_s = mu_s0 * mu / mu0 (the scene's break-away ratio kept); with an uncertainty of its
    own it is drawn like any relative parameter.  Catches the ratio inverted or taken of the
    wrong parameter, a follower drawn anyway."""
    params = perturbable(_scene(drive2={"friction": "lugre"}))
    nominal = {p.name: p.nominal for p in params}
    values = draw(params, uncertainties(params, 0.4), 3, 1)
    ratio = values["drive2.mu"] / nominal["drive2.mu"]
    assert ratio != 1.0
    assert values["drive2.mu_s"] == pytest.approx(nominal["drive2.mu_s"] * ratio, rel=1e-15)
    assert values["drive2.mu_s"] / values["drive2.mu"] == pytest.approx(nominal["drive2.mu_s"] / nominal["drive2.mu"],
                                                                        rel=1e-14)
    own = draw(params, uncertainties(params, 0.4, {"drive2.mu_s": 0.1}), 3, 1)
    assert own["drive2.mu_s"] == nominal["drive2.mu_s"] * (1.0 + 0.1 * _xi(3, 1, "drive2.mu_s", "uniform"))
    with pytest.raises(ValueError, match=r"parameter drive2.mu_s follows 'drive2.mu', which is not drawn with it"):
        draw([p for p in params if p.name != "drive2.mu"], uncertainties(params, 0.4), 3, 1)


def test_the_perturbed_scene_sets_the_values_and_keeps_the_drives_designs_nominal():
    """Every drawn value on its component; each perturbed motor parameter's design twin at the
    nominal value (or at the scene's own design value); the controller's side untouched.
    Catches a value set on the wrong instance, the design parameter set to the drawn value,
    a scene's own design value overwritten."""
    scene = _scene(drive1={"kt_design": 0.0601})
    params = perturbable(scene)
    values = draw(params, uncertainties(params, 0.4), 11, 2)
    changed = perturbed(scene, params, values)
    nominal = {p.name: p.nominal for p in params}
    for name in ("traj", "deriv", "ctrl", "obs1", "obs2"):
        assert changed.system.component(name) is scene.system.component(name)
    for name in ("drive1", "drive2"):
        got = changed.system.component(name).parameters
        drawn = {f: values[f"{name}.{f}"] for f in MOTOR}
        design = {f"{f}_design": nominal[f"{name}.{f}"] for f in ("R", "L", "kt", "ke", "b")}
        if name == "drive1":
            design["kt_design"] = 0.0601
        assert got == {**scene.system.component(name).parameters, **drawn, **design}
    plant = changed.system.component("plant").parameters
    assert plant == {**scene.system.component("plant").parameters,
                     **{p.variable: values[p.name] for p in params if p.instance == "plant"}}


def test_a_plant_without_a_preset_is_the_thesis_sim_preset():
    """Catches the FiveBarPlant's default preset (``thesis_sim``, as the FMU declares) lost."""
    scene = get_scene("bench_circle_TCMDx")
    components = tuple(replace(c, parameters={k: v for k, v in c.parameters.items() if k != "preset"})
                       if c.name == "plant" else c for c in scene.system.components)
    params = {p.name: p.nominal for p in perturbable(replace(scene, system=replace(scene.system,
                                                                                  components=components)))}
    thesis = get_preset("thesis_sim")
    assert params["plant.l0"] == thesis.l0 and params["plant.chain2_m1"] == thesis.chain2.m1
    assert thesis.chain2.m1 != get_preset("bench").chain2.m1


def test_a_perturb_file_is_read_and_each_bad_entry_refused_naming_file_and_key(tmp_path):
    """Catches the checks of the file (unknown key, negative or non-numeric value, a
    distribution not known) dropped or loosened; ints are read as floats."""
    f = tmp_path / "p.toml"
    f.write_text('distribution = "normal"\n[uncertainty]\n"drive?.R" = 1\n"plant.l0" = 0.002\n')
    assert load_perturb_file(f) == {"uncertainty": {"drive?.R": 1.0, "plant.l0": 0.002}, "distribution": "normal"}
    f.write_text('[uncertainty]\n"drive1.R" = 0.1\n')
    assert load_perturb_file(f) == {"uncertainty": {"drive1.R": 0.1}, "distribution": None}
    for text, message in (('spread = 1\n', r"unknown key\(s\) \['spread'\]"),
                          ('[uncertainty]\n"a" = true\n', r"uncertainty 'a' = True must be a finite number >= 0"),
                          ('[uncertainty]\n"a" = -0.5\n', r"uncertainty 'a' = -0.5 must be"),
                          ('[uncertainty]\n"a" = nan\n', r"uncertainty 'a' = nan must be"),
                          ('distribution = "cauchy"\n', r"distribution = 'cauchy'; valid: uniform, normal"),
                          ('uncertainty = 3\n', r"'uncertainty' must be a table"),
                          ('[uncertainty\n', r"Expected '\]'")):
        f.write_text(text)
        with pytest.raises(ValueError, match=rf"--perturb {f}: " + message):
            load_perturb_file(f)
