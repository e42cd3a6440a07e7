"""Values moved between an instance and the master's slot array: the few fast getters both the
stepper (:mod:`fmus.cosim.stepper`) and the in-process back end (:mod:`fmus.cosim.backends`) use."""
from __future__ import annotations

import operator


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
