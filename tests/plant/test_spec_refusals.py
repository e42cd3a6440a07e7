"""plant/spec.py: every refusal of the format not read elsewhere, word for word: the source,
the line of the key (none when the key is nowhere in the file), the dotted key, the value as
written and the reason (docs/spec.md).  Catches a refusal naming the parent table instead of
the key, the wrong value or line, a check reversed or a message changed."""
from __future__ import annotations

import pytest

from plant import spec as plant_spec
from tests.plant.test_spec import GOOD    # the smallest two-link chain; the line numbers below are counted on it

TWO_LINKS = GOOD[GOOD.index("[[chains.links]]"):]
UNKNOWN_TOP = "unknown key; valid: chains, description, gravity, name, platform"


@pytest.mark.parametrize("old, new, line, key, value, why", [
    ('name = "t"', "name = 5", 1, "name", 5, "must be a string"),
    ('name = "t"', 'name = "t"\nnmae = "u"', 2, "nmae", "u", UNKNOWN_TOP),
    ('name = "t"', 'name = "t"\nplatform = 3', 2, "platform", 3, "must be a table"),
    ("gravity = [0.0, -9.81, 0.0]", "gravity = [0.0, -9.81]", 2, "gravity", [0.0, -9.81],
     "must be a list of 3 numbers"),
    ('name = "q2"', 'name = "q2"\njoint = "S"', 15, "chains[0].links[1].joint", "S",
     "must be 'R' (revolute) or 'P' (prismatic)"),
    ("mass = 0.2", "mass = 0.2\ninertia = [1.0, -1.0, 0.0]", 17, "chains[0].links[1].inertia",
     [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 0.0]], "must be symmetric positive semi-definite [kg m2]"),
    ("mass = 0.2", "mass = 0.2\npoint_masses = [1.0]", 17, "chains[0].links[1].point_masses[0]", 1.0,
     "must be a table"),
    ("mass = 0.2", "mass = 0.2\n\n[[chains.links.point_masses]]\nmass = 0.1\nat = [0.0, 0.0, 0.0]\nwhere = 1", 21,
     "chains[0].links[1].point_masses[0].where", 1, "unknown key; valid: at, mass"),
    ("actuated = true", 'actuated = true\ninput = "2x"', 10, "chains[0].links[0].input", "2x",
     "must be an identifier (letters, digits, _)"),
    # the key is the whole array of chains, which no single header defines: no line
    ("actuated = true", "actuated = false", None, "chains", "...",
     "no joint is actuated (set actuated = true on at least one link)"),
    ('name = "c"', 'name = "c"\nrotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]', 6,
     "chains[0].rotation", [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]],
     "must be a rotation matrix (orthonormal, det +1)"),
])
def test_each_refusal_names_its_line_key_value_and_reason_word_for_word(old, new, line, key, value, why):
    text = GOOD.replace(old, new, 1)
    assert text != GOOD
    with pytest.raises(plant_spec.SpecError) as info:
        plant_spec.loads(text, source="t.toml")
    err = info.value
    assert (err.source, err.line, err.key, err.value) == ("t.toml", line, key, value)
    where = "t.toml" if line is None else f"t.toml, line {line}"
    assert str(err) == f"{where}: {key} = {value!r}: {why}"


def test_a_spec_without_chains_is_refused_without_a_line():
    """No [[chains]] anywhere: no line to name, the message is the source's."""
    with pytest.raises(plant_spec.SpecError) as info:
        plant_spec.loads('name = "t"\n', source="t.toml")
    assert (info.value.line, info.value.key) == (None, "chains")
    assert str(info.value) == "t.toml: chains = None: need at least one [[chains]] table"


def test_a_chain_without_links_is_refused_at_its_table():
    """The key chains[0].links is nowhere: the line is its chain's [[chains]] header (line 4)."""
    text = GOOD[:GOOD.index("[[chains.links]]")] + "[[chains]]\nname = \"d\"\n" + TWO_LINKS
    with pytest.raises(plant_spec.SpecError) as info:
        plant_spec.loads(text, source="t.toml")
    assert str(info.value) == "t.toml, line 4: chains[0].links = None: need at least one [[chains.links]] table"


def test_two_chains_without_a_platform_are_refused_naming_the_count():
    """Two chains are a parallel mechanism: without [platform] nothing couples them."""
    text = GOOD + "\n[[chains]]\nname = \"d\"\n\n" + TWO_LINKS.replace('"q1"', '"p1"').replace('"q2"', '"p2"').replace(
        "actuated = true", 'actuated = true\ninput = "taup1"')
    with pytest.raises(plant_spec.SpecError) as info:
        plant_spec.loads(text, source="t.toml")
    assert str(info.value) == "t.toml: platform = None: 2 chains need a [platform] to couple them"


@pytest.mark.parametrize("links, shown", [("[]", []), ('"q1"', "q1")])
def test_links_that_are_empty_or_not_a_list_are_refused_as_no_links(links, shown):
    """links must be a non-empty list of tables: an empty list, or a truthy non-list, is
    refused at its own line (6, under the chain's name) with the value as written."""
    text = GOOD[:GOOD.index("[[chains.links]]")].replace('name = "c"', f'name = "c"\nlinks = {links}')
    with pytest.raises(plant_spec.SpecError) as info:
        plant_spec.loads(text, source="t.toml")
    assert str(info.value) == (f"t.toml, line 6: chains[0].links = {shown!r}: "
                               "need at least one [[chains.links]] table")


@pytest.mark.parametrize("chains, shown", [("[]", []), ("7", 7)])
def test_chains_that_are_empty_or_not_a_list_are_refused_as_no_chains(chains, shown):
    with pytest.raises(plant_spec.SpecError) as info:
        plant_spec.loads(f'name = "t"\nchains = {chains}\n', source="t.toml")
    assert str(info.value) == f"t.toml, line 2: chains = {shown!r}: need at least one [[chains]] table"
