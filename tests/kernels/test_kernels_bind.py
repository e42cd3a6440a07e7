"""kernels.bind: a C function with some arguments fixed and the others given per call gives,
for every number and place of per-call arguments (the 1-, 2-, 3-slot fast paths and the
general one), the same bits as the function called with all its arguments; a wrong count is
refused naming the function."""
from __future__ import annotations

import gc
import itertools
import re

import numpy as np
import pytest

import kernels
from motor import kernel as motor_kernel

#: pc_drive_armature_rate(R, L, ke, v, i, omega) = (v - R i - ke omega) / L: every argument
#: changes the result, so a value put into another's slot shows.
VALUES = (1.3, 2.7e-3, 0.061, 11.5, -0.42, 37.0)


@pytest.mark.parametrize("per_call", [c for n in range(7) for c in itertools.combinations(range(6), n)],
                         ids=lambda c: "-".join(map(str, c)) or "none")
def test_every_choice_of_per_call_arguments_is_the_direct_call(per_call):
    """Catches a per-call value written into another slot (the 3-slot path giving its first value
    twice), a slot left at its last value, a fixed argument dropped or moved."""
    function = motor_kernel.armature_rate
    direct = function(*VALUES)
    assert direct == (VALUES[3] - VALUES[0] * VALUES[4] - VALUES[2] * VALUES[5]) / VALUES[1]
    call = kernels.bind(function, *(kernels.PER_CALL if k in per_call else v for k, v in enumerate(VALUES)))
    assert call(*(VALUES[k] for k in per_call)) == direct
    other = [v * 1.5 + 0.25 for v in VALUES]              # a second call: every slot takes its new value
    again = [other[k] if k in per_call else VALUES[k] for k in range(6)]
    assert call(*(other[k] for k in per_call)) == function(*again)


def test_a_wrong_number_of_arguments_is_refused_naming_the_function():
    """Catches a bind that accepts too few arguments (C would read garbage) or too many."""
    for arguments in (VALUES[:5], VALUES + (1.0,)):
        message = f"pc_drive_armature_rate takes 6 arguments, {len(arguments)} bound"
        with pytest.raises(TypeError, match=re.escape(message)):
            kernels.bind(motor_kernel.armature_rate, *arguments)


def test_owned_calls_are_made_once_per_buffers_and_dropped_with_their_owner():
    """kernels.owned makes an owner's calls once, again only when its buffers are other
    arrays (by identity, not value), and forgets them when the owner is collected.  Catches a
    cache that never hits, answers for other buffers, or keeps a dead owner's entry (whose
    id a new object may take)."""
    class Owner:
        pass

    owner, a, b = Owner(), np.zeros(2), np.zeros(3)
    made = []

    def make(*buffers):
        made.append(buffers)
        return len(made)

    assert kernels.owned(owner, (a, b), make) == 1 and kernels.owned(owner, (a, b), make) == 1
    assert kernels.owned(owner, (a, np.zeros(3)), make) == 2 and made[1][0] is a
    assert kernels.owned(owner, (a, b), make) == 3 and len(made) == 3
    key = id(owner)
    assert key in kernels._OWNED
    del owner
    gc.collect()
    assert key not in kernels._OWNED


def test_an_owner_whose_buffers_never_change_is_forgotten_when_collected():
    """The usual life of an owner: its calls made once, on the same buffers ever after, then the
    owner collected; its entry goes with it (seed 3901's [95]: the finalizer registered only
    when the buffers change passed the test above, whose buffers do change).  An entry kept
    would hold the buffers alive and answer a new object that takes the dead owner's id."""
    class Owner:
        pass

    owner, a = Owner(), np.zeros(2)
    assert kernels.owned(owner, (a,), lambda *b: "calls") == "calls"
    assert kernels.owned(owner, (a,), lambda *b: "again") == "calls"
    key = id(owner)
    del owner
    gc.collect()
    assert key not in kernels._OWNED
