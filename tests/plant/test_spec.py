"""Mechanism specs (plant/spec.py): the format's errors, and the shipped serial specs
against the closed forms of seed 001 (54), (57)-(63) and the balanced RR (64)-(71),
derived here from (62)-(63) where the seed has typos (docs/spec.md)."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from plant import spec as plant_spec
from plant.serial import RigidLink, SerialChain, chain_dynamics, with_point_mass
from plant.specsim import serial_terms

#: Table 3 links (the shipped RR specs use them) and gravity along -y.
L1, L2, LG1, LG2, M1, M2, JZ1, JZ2 = 0.12, 0.15, 0.06, 0.075, 0.143, 0.171, 1.716e-4, 3.206e-4
G = 9.81


def rr_closed_form(q, dq, cm1=0.0, at1=0.0, cm2=0.0, at2=0.0):
    """M#, v#, g# of the RR with point masses cm1 at at1 from joint 1 (on link 1) and cm2 at at2
    from joint 2 (on link 2): seed 001 (57)-(63); cm = 0 gives (54).  Written from the seed,
    with its (54) typo m1 -> m2 in the velocity terms corrected."""
    c1, c2, s2, c12 = math.cos(q[0]), math.cos(q[1]), math.sin(q[1]), math.cos(q[0] + q[1])
    k = cm2 * at2 + M2 * LG2
    M = np.array([
        [JZ1 + JZ2 + cm1 * at1 ** 2 + cm2 * at2 ** 2 + M1 * LG1 ** 2 + M2 * LG2 ** 2 + (cm2 + M2) * L1 ** 2
         + 2 * L1 * c2 * k,                                                                   # (57)
         JZ2 + cm2 * at2 * (L1 * c2 + at2) + M2 * LG2 * (L1 * c2 + LG2)],                     # (58)
        [0.0, JZ2 + cm2 * at2 ** 2 + M2 * LG2 ** 2]])                                          # (59)
    M[1, 0] = M[0, 1]
    v = np.array([-k * L1 * s2 * dq[1] * (2 * dq[0] + dq[1]), k * L1 * s2 * dq[0] ** 2])    # (60-61)
    g = G * np.array([(cm1 * at1 + M1 * LG1 + (cm2 + M2) * L1) * c1 + k * c12, k * c12])      # (62-63)
    return M, v, g


def balancing(cm1, cm2):
    """(L1, L2) that make (62)-(63) vanish: the corrected (64)."""
    return -(M1 * LG1 + (cm2 + M2) * L1) / cm1, -M2 * LG2 / cm2


def random_states(n=20, seed=1):
    rng = np.random.default_rng(seed)
    return [(rng.uniform(-math.pi, math.pi, 2), rng.uniform(-10, 10, 2)) for _ in range(n)]


def test_rr_equals_the_closed_form_54():
    """Catches the spec plant's serial dynamics (mass matrix, velocity or gravity terms) of an RR arm
    differing from the closed form (5.4) beyond 1e-12."""
    spec = plant_spec.load("rr")
    for q, dq in random_states():
        dyn = serial_terms(spec, q, dq)
        M, v, g = rr_closed_form(q, dq)
        assert np.max(np.abs(dyn.M - M)) < 1e-12
        assert np.max(np.abs(dyn.v - v)) < 1e-12
        assert np.max(np.abs(dyn.g - g)) < 1e-12


def test_rr_with_counter_masses_equals_57_to_63():
    """Catches counter masses placed on the wrong side or link (negative offsets) in the spec plant's
    dynamics, against (5.7)-(5.63)."""
    spec = plant_spec.load("rr_counter_masses")   # M1 = 0.3 kg at L1 = -0.05 m, M2 = 0.1 kg at L2 = -0.04 m
    for q, dq in random_states(seed=2):
        dyn = serial_terms(spec, q, dq)
        M, v, g = rr_closed_form(q, dq, 0.3, -0.05, 0.1, -0.04)
        assert np.max(np.abs(dyn.M - M)) < 1e-12
        assert np.max(np.abs(dyn.v - v)) < 1e-12
        assert np.max(np.abs(dyn.g - g)) < 1e-12
        assert np.max(np.abs(g)) > 1e-2   # not balanced: gravity loads the joints


def test_balanced_rr_has_no_gravity_nor_velocity_terms_and_a_constant_mass_matrix():
    """Catches the balancing formula (64, as corrected) or the spec's counter masses being off: gravity or
    velocity terms left, or a pose-dependent mass matrix."""
    spec = plant_spec.load("rr_balanced")          # M1 = 0.5 kg, M2 = 0.2 kg by the corrected (64)
    at1, at2 = balancing(0.5, 0.2)
    assert (at1, at2) == pytest.approx((-0.1062, -0.064125), abs=1e-15)   # the spec's comment
    k = M2 * (0.2 + M2) * LG2 ** 2 / 0.2
    constant = np.array([
        [JZ1 + JZ2 + M1 * LG1 ** 2 + M2 * LG2 ** 2 + L1 ** 2 * (0.2 + M2) + M2 ** 2 * LG2 ** 2 / 0.2
         + (M1 * LG1 + (0.2 + M2) * L1) ** 2 / 0.5, JZ2 + k],     # (65) corrected, (66)
        [JZ2 + k, JZ2 + k]])
    for q, dq in random_states(seed=3):
        dyn = serial_terms(spec, q, dq)
        assert np.max(np.abs(dyn.g)) < 1e-12                      # (69-70)
        assert np.max(np.abs(dyn.v)) < 1e-12                      # (67-68)
        assert np.max(np.abs(dyn.M - constant)) < 1e-12           # (65-66), (71)


def test_the_seeds_printed_64_and_65_are_typos():
    """(64) as printed (m2 l2 in L1's numerator) leaves gravity on joint 1; (65) as printed
    (m1 lg2^2, no m1 lg1^2 and m2 lg2^2) is not the balanced chain's M#_11."""
    at1_printed = -(0.2 * L1 + M1 * LG1 + M2 * L2) / 0.5
    at2 = -M2 * LG2 / 0.2
    links = (with_point_mass(RigidLink(M1, (LG1 - L1, 0, 0), np.diag([0, JZ1, JZ1])), 0.5, (at1_printed - L1, 0, 0)),
             with_point_mass(RigidLink(M2, (LG2 - L2, 0, 0), np.diag([0, JZ2, JZ2])), 0.2, (at2 - L2, 0, 0)))
    from plant.serial import DHJoint
    chain = SerialChain((DHJoint("R", L1, 0.0), DHJoint("R", L2, 0.0)), links)
    dyn = chain_dynamics(chain, [0.3, 0.4], [0.0, 0.0], [0, -G, 0])
    assert abs(dyn.g[0]) > 1e-3
    printed_65 = (JZ1 + JZ2 + M1 * LG2 ** 2 + L1 ** 2 * (0.2 + M2) + M2 ** 2 * LG2 ** 2 / 0.2
                  + (M1 * LG1 + (0.2 + M2) * L1) ** 2 / 0.5)
    balanced = serial_terms(plant_spec.load("rr_balanced"), [0.3, 0.4], [0.0, 0.0]).M[0, 0]
    assert abs(balanced - printed_65) > 1e-4


# --- the format's errors -------------------------------------------------------------------

GOOD = """name = "t"
gravity = [0.0, -9.81, 0.0]

[[chains]]
name = "c"

[[chains.links]]
name = "q1"
actuated = true
a = 0.1
mass = 0.1

[[chains.links]]
name = "q2"
a = 0.1
mass = 0.2
"""


@pytest.mark.parametrize("old, new, line, key, value", [
    ("mass = 0.2", "mass = -0.2", 16, "chains[0].links[1].mass", "-0.2"),
    ("mass = 0.2", "mas = 0.2", 16, "chains[0].links[1].mas", "0.2"),
    ("a = 0.1\nmass = 0.1", "a = 0.1\nmass = 0.1\ninertia = [1.0, 2.0]", 12, "chains[0].links[0].inertia",
     "[1.0, 2.0]"),
    ('name = "c"', 'name = "c"\nrotation = [[1, 0, 0], [0, 1, 0], [0, 0, 2]]', 6, "chains[0].rotation", "2"),
    ('name = "q2"', 'name = "q1"', 14, "chains[0].links[1].name", "q1"),
    ('name = "q2"', 'name = "2x"', 14, "chains[0].links[1].name", "2x"),
    ('name = "q2"\n', '', 13, "chains[0].links[1].name", "= None: missing (required)"),   # was refused as a path
    ("mass = 0.2", "mass = 0.2\n\n[[chains.links.point_masses]]\nat = [0.0, 0.0, 0.1]", 18,
     "chains[0].links[1].point_masses[0].mass", "= None: missing (required)"),    # no value: None, not 0
    ('joint', 'joint', None, "", ""),   # unchanged: loads
    ('gravity = [0.0, -9.81, 0.0]', 'gravity = [0.0, "down", 0.0]', 2, "gravity", "down"),
    ('actuated = true', 'actuated = "yes"', 9, "chains[0].links[0].actuated", "yes"),
    ('name = "q2"', 'name = "q2"\nactuated = true\ninput = "tau1"', 16, "chains[0].links[1].input", "tau1"),
])
def test_a_bad_value_is_named_with_its_line_key_and_value(old, new, line, key, value):
    """Catches a spec error that names another line or key than the offending one, or omits its value (a
    negative mass, a misspelled key, a wrong type, a required key missing)."""
    text = GOOD.replace(old, new)
    if line is None:
        assert plant_spec.loads(text).chains[0].chain.dof == 2
        return
    with pytest.raises(plant_spec.SpecError) as info:
        plant_spec.loads(text, source="t.toml")
    err = info.value
    assert (err.line, err.key) == (line, key)
    assert str(err).startswith(f"t.toml, line {line}: {key} = ")
    assert value in str(err)


def test_a_syntax_error_keeps_the_line():
    """Catches a spec loader that loses the TOML syntax error's line, or fills the error's
    fields (key, value) with its text."""
    with pytest.raises(plant_spec.SpecError, match=r"^t.toml, line 10: TOML syntax") as info:
        plant_spec.loads(GOOD.replace("a = 0.1\nmass = 0.1", "a = 0.1 0.2\nmass = 0.1"), source="t.toml")
    assert (info.value.source, info.value.line, info.value.key, info.value.value) == ("t.toml", 10, "", None)


def test_a_spec_is_found_by_name_or_path_and_an_unknown_name_is_refused_listing_the_shipped(tmp_path):
    """Catches a lookup that takes a path for a name (or the other way round), or a refusal
    that does not name what was asked for and what is shipped."""
    shipped = sorted(p.name.removesuffix(".toml") for p in plant_spec.SPEC_DIR.iterdir() if p.suffix == ".toml")
    assert plant_spec.shipped_specs() == shipped and "bench_5r" in shipped
    assert plant_spec.spec_path("bench_5r") == plant_spec.SPEC_DIR / "bench_5r.toml"
    own = tmp_path / "bench_5r"          # an existing file of that name is a path, not the shipped spec
    own.write_text(GOOD)
    assert plant_spec.spec_path(own) == own and plant_spec.load(own).chains[0].chain.dof == 2
    assert plant_spec.spec_path("elsewhere/new.toml") == Path("elsewhere/new.toml")
    with pytest.raises(FileNotFoundError) as info:
        plant_spec.load("bench_6r")
    assert str(info.value) == ("no spec file 'bench_6r' and no shipped spec of that name "
                               f"(shipped: {', '.join(shipped)})")


def test_a_parallel_spec_needs_as_many_actuators_as_dof():
    """Catches a parallel spec accepted with more platform freedoms than actuators."""
    text = plant_spec.load("thesis_sim_5r").text.replace('independent = ["x", "y"]', 'independent = ["x", "y", "z"]')
    with pytest.raises(plant_spec.SpecError, match=r"line 13: platform.independent = \['x', 'y', 'z'\]: 3 degrees "
                                                   r"of freedom but 2 actuated"):
        plant_spec.loads(text, source="t.toml")


def test_every_shipped_spec_loads():
    """Catches a shipped spec that no longer loads, or is loaded under another name."""
    names = plant_spec.shipped_specs()
    assert {"thesis_sim_5r", "bench_5r", "rr", "rr_counter_masses", "rr_balanced", "balanced_5r", "delta3"} <= set(names)
    for name in names:
        assert plant_spec.load(name).name == name


def test_build_plant_cli_names_the_bad_line(tmp_path):
    """Catches build-plant writing an FMU from a bad or serial spec, or erring without the line."""
    import subprocess
    import sys
    bad = tmp_path / "bad.toml"
    bad.write_text(plant_spec.load("thesis_sim_5r").text.replace("mass = 0.171", "mass = -0.171", 1))
    out = subprocess.run([sys.executable, "-m", "parcosim", "build-plant", str(bad), str(tmp_path / "x.fmu")],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 2 and out.stderr.count("\n") == 1
    assert f"{bad}, line 32: chains[0].links[1].mass = -0.171: must be >= 0" in out.stderr
    assert not (tmp_path / "x.fmu").exists()
    serial = subprocess.run([sys.executable, "-m", "parcosim", "build-plant", "rr", str(tmp_path / "x.fmu")],
                            capture_output=True, text=True, timeout=300)
    assert serial.returncode == 2 and "serial chain" in serial.stderr


@pytest.mark.parametrize("rotation", ["[[1, 0, 0], [0, 1, 0]]", "[[1, 0, 0], [0, 1, 0], [0, 0]]", "[1, 0, 0]"])
def test_a_rotation_not_3_by_3_is_refused_with_its_value_as_written(rotation):
    """docs/spec.md: ``rotation`` is a 3x3 list of lists.  Catches a wrong shape accepted (numpy would
    broadcast or fail later, far from the line) or refused with the reason and the value swapped."""
    text = GOOD.replace('name = "c"', f'name = "c"\nrotation = {rotation}')
    with pytest.raises(plant_spec.SpecError) as info:
        plant_spec.loads(text, source="t.toml")
    err = info.value
    assert (err.line, err.key, err.value) == (6, "chains[0].rotation", json.loads(rotation))
    assert str(err).endswith(": must be a 3x3 list of lists")


def test_gravity_and_chain_names_default_as_the_format_says():
    """docs/spec.md: gravity defaults to 0 (no gravity terms at any pose, (57)-(63) with g = 0)
    and a chain without a name is ``chain<i>`` counted from 1."""
    text = GOOD.replace('gravity = [0.0, -9.81, 0.0]\n', "").replace('name = "c"\n', "")
    spec = plant_spec.loads(text, source="t.toml")
    assert spec.chains[0].name == "chain1"
    assert tuple(spec.gravity) == (0.0, 0.0, 0.0)
    for q, dq in random_states(5):
        assert np.max(np.abs(serial_terms(spec, q, dq).g)) == 0.0


def test_repeated_independent_axes_are_refused_naming_the_entry():
    """Catches a spec accepted with the same platform axis twice."""
    text = (plant_spec.SPEC_DIR / "bench_5r.toml").read_text()
    assert 'independent = ["x", "y"]' in text
    with pytest.raises(ValueError, match=r"platform\.independent.*distinct"):
        plant_spec.loads(text.replace('independent = ["x", "y"]', 'independent = ["x", "x"]'), source="b.toml")


@pytest.mark.parametrize("new, why", [
    ("mass = 0.0", None),                           # the bound itself: a massless link loads
    ("mass = 0", None),                             # a TOML integer is a number
    ("mass = -1e-300", "must be >= 0"),
    ("mass = inf", "must be a finite number"),
    ("mass = nan", "must be a finite number"),
    ("mass = true", "must be a finite number"),     # a bool is not a number here
    ("mass = 0.2\nrotor_inertia = -1e-9", "must be >= 0"),
    ("mass = 0.2\nrotor_inertia = 0.0", None),
    ("mass = 0.2\ngear_ratio = -2.0", None),        # a reversing gear: no bound
])
def test_a_number_is_refused_only_below_its_bound_or_when_not_finite(new, why):
    """The bounds of the format's numbers at their edges: >= 0 admits 0 itself and refuses
    the least negative value; inf, nan and a bool are not finite numbers; an unbounded key
    (gear_ratio) takes a negative value.  Catches a bound shifted by the least step or
    turned strict, a finiteness check that lets inf or nan through."""
    text = GOOD.replace("mass = 0.2", new)
    if why is None:
        assert plant_spec.loads(text).chains[0].chain.dof == 2
        return
    with pytest.raises(plant_spec.SpecError, match=why) as info:
        plant_spec.loads(text, source="t.toml")
    assert info.value.key.startswith("chains[0].links[1].")
