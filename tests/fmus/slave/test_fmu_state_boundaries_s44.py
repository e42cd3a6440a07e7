"""Laying a state tree over a live instance (``fmus.slave.state.apply``): each refusal's
condition at its edge (issue 31, training seed 4451 [3] and its siblings).

A shared value (a :class:`~fmus.slave.state_format.Ref`) may stand where the instance holds a
container only when it is a container of the same type; a list or tuple of the state may be
longer than the instance's (the items beyond take no template), exactly as long, or shorter.
"""
from __future__ import annotations

import numpy as np
import pytest

from fmus.slave import state as fmustate
from fmus.slave import state_format as stateformat


@pytest.mark.parametrize("held, shared, described", [
    ({"x": 1.0}, [2.0], "holds a builtins.dict"),
    ([1.0], {"x": 2.0}, "holds a builtins.list"),
    (np.zeros(1), [2.0], "has an array of dtype float64 and shape (1,)"),
])
def test_a_reference_to_another_container_type_than_the_instance_holds_is_refused_naming_both(held, shared,
                                                                                               described):
    """The instance holds a container at ``b`` and the state makes ``b`` share a container of
    another type: refused, naming the place, the shared type and what the instance holds
    (never silently replacing the instance's container)."""
    template, tree = {"a": shared, "b": held}, {"a": shared, "b": stateformat.Ref(1)}
    kind = type(shared).__name__
    with pytest.raises(fmustate.StateMismatch) as info:
        fmustate.apply(template, tree)
    assert str(info.value) == f"b: the state shares a {kind} here, this instance {described}"


@pytest.mark.parametrize("held, shared", [([1.0], [2.0, 3.0]), ({"x": 1.0}, {"y": 2.0})])
def test_a_reference_to_a_container_of_the_type_the_instance_holds_is_taken_and_shared(held, shared):
    """The same type on both sides: ``b`` becomes the very container rebuilt at ``a``."""
    template = {"a": type(shared)(), "b": held}
    got = fmustate.apply(template, {"a": shared, "b": stateformat.Ref(1)})
    assert got["b"] is got["a"] and got["a"] == shared


@pytest.mark.parametrize("kind", [tuple, list])
@pytest.mark.parametrize("length", [0, 1, 2, 3])
def test_a_sequence_of_the_state_of_any_length_beside_the_instances_two_items_is_read_back(kind, length):
    """The instance holds two items; the state's sequence may hold fewer, exactly two or more
    (the items past the instance's last are read with no template): each is read back exactly,
    a list into the instance's own list."""
    held = kind([7.0, 8.0])
    data = kind(float(k) + 0.5 for k in range(length))
    got = fmustate.apply({"s": held}, {"s": data})
    assert type(got["s"]) is kind and got["s"] == data
    if kind is list:
        assert got["s"] is held


def test_a_number_where_the_instance_holds_another_kind_of_number_past_its_items_is_not_checked_against_it():
    """Items past the instance's sequence have no template, so any leaf kind is taken there,
    while within it the kind must match (a bool where a float stands is refused, naming it)."""
    got = fmustate.apply({"s": (1.0,)}, {"s": (2.0, True)})
    assert got["s"] == (2.0, True)
    with pytest.raises(fmustate.StateMismatch, match=r"^s\[0\]: the state holds the bool True, this instance "):
        fmustate.apply({"s": (1.0,)}, {"s": (True, 2.0)})


@pytest.mark.parametrize("tree, named", [
    ({"a": 3.0}, "missing b"),
    ({"a": 3.0, "b": 4.0, "c": 5.0}, "unknown c"),
    ({"a": 3.0, "c": 5.0}, "missing b; unknown c"),
])
def test_a_state_whose_attributes_are_not_the_instances_is_refused_naming_each_and_the_instance_is_kept(tree, named):
    """An attribute missing, one unknown, or both: refused naming them, the instance's own
    attributes left as they were. Catches a state with only missing or only unknown attributes
    laid over the instance (attributes dropped or made up), the whole set taken for both."""
    template = {"a": 1.0, "b": 2.0}
    with pytest.raises(fmustate.StateMismatch) as info:
        fmustate.apply(template, tree)
    assert str(info.value) == f"the state's attributes differ from this instance's: {named}"
    assert template == {"a": 1.0, "b": 2.0}
