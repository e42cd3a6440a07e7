"""fmus/cosim/slots.py, the values moved between the master's slot array and an instance, against
plain indexing written here: every getter and setter for 0, 1, 2 and 3 slots (each has its own
branch), slots out of order, the spans of consecutive slots and the refusal of others (issue
31: "fmus other"; values read back exactly)."""
from __future__ import annotations

import re

import pytest

from fmus.cosim.slots import attribute_pull, gatherer, gathering_pull, span

VALUES = [10.5, -1.25, 3.0, 7.75, 0.0, 2.5]


@pytest.mark.parametrize("slots", [(), (4,), (3, 1), (5, 0, 2), [2, 3, 4, 5]])
def test_gathering_takes_the_slots_values_in_the_slots_order(slots):
    """Catches a slot dropped or repeated, the order of the slots lost, and one slot given as a
    bare value instead of a tuple."""
    expected = tuple(VALUES[s] for s in slots)
    assert tuple(gatherer(slots)(VALUES)) == expected
    got = []
    gathering_pull(got.append, slots)(VALUES)
    assert [tuple(g) for g in got] == [expected]


@pytest.mark.parametrize("slots", [(4,), (3, 1), (5, 0, 2), (0, 1, 2, 3)])
def test_an_attribute_pull_sets_each_name_to_its_slots_value_as_a_float(slots):
    """Catches a name given another slot's value (the two-input branch written out), a value
    left an int, and a name of the attributes not asked for written."""
    names = [f"u{k}" for k in range(len(slots))]
    mixed = [int(v) if v.is_integer() else v for v in VALUES]       # ints among the values
    attributes = {"other": "kept"}
    attribute_pull(attributes, names, slots)(mixed)
    assert attributes == {"other": "kept", **{n: float(mixed[s]) for n, s in zip(names, slots)}}
    assert all(type(attributes[n]) is float for n in names)


def test_a_span_is_the_slice_of_consecutive_slots_and_others_are_refused():
    """Catches an off-by-one end, an empty span not empty, and slots with a gap taken as a slice."""
    assert span([3, 4, 5]) == slice(3, 6) and VALUES[span([3, 4, 5])] == VALUES[3:6]
    assert span([2]) == slice(2, 3) and span([]) == slice(0, 0)
    for bad in ([3, 5], [4, 3], [0, 0]):
        with pytest.raises(AssertionError, match=re.escape(f"output slots {bad} are not consecutive")):
            span(bad)
