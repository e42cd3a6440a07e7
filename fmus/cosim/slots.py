"""Values moved between an instance and the master's slot array: the few fast getters and
setters both the stepper (:mod:`fmus.cosim.stepper`) and the in-process back end
(:mod:`fmus.cosim.backends`) use."""
from __future__ import annotations

import operator
from typing import Callable


def gatherer(slots):
    """``values -> tuple of values[i] for i in slots`` (one C call: operator.itemgetter)."""
    if len(slots) == 1:
        slot = slots[0]
        return lambda values: (values[slot],)
    return operator.itemgetter(*slots) if slots else (lambda values: ())


def span(slots) -> slice:
    """The slice of ``slots``, consecutive by construction (:class:`fmus.cosim.stepper.Stepper` numbers each
    instance's outputs together)."""
    first = slots[0] if slots else 0
    if list(slots) != list(range(first, first + len(slots))):
        raise AssertionError(f"output slots {slots} are not consecutive")
    return slice(first, first + len(slots))


def attribute_pull(attributes: dict, names: list, slots) -> Callable:
    """``pull(values)``: ``attributes[name] = float(values[slot])`` for each input, written out
    for one and two inputs (the most common: a store each, no loop), a loop for more (cheaper
    than one dict update of zip and map objects; measured)."""
    pairs = tuple(zip(names, slots))
    if len(pairs) == 1:
        (name, slot), = pairs

        def pull(values):
            attributes[name] = float(values[slot])
    elif len(pairs) == 2:
        (name0, slot0), (name1, slot1) = pairs

        def pull(values):
            attributes[name0] = float(values[slot0])
            attributes[name1] = float(values[slot1])
    else:
        def pull(values):
            for name, slot in pairs:
                attributes[name] = float(values[slot])
    return pull


def gathering_pull(set_inputs: Callable, slots) -> Callable:
    """``pull(values)``: ``set_inputs`` of the values of ``slots``."""
    gather = gatherer(slots)
    return lambda values: set_inputs(gather(values))
