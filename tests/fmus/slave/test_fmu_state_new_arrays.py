"""An array of a state where the live instance holds nothing yet (:func:`fmus.slave.state.apply`:
an attribute still None, built later in the run): taken as the state's when every number
of it is finite, plain or record array alike, and refused naming the first place that is
not, since no value of the instance can vouch for it; where the instance holds an array,
only the non-finite values it holds at the same places pass (seed 4001's survivor [108],
the template's test ``and`` made ``or``: an array over None then crashed on the template)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fmus.slave import state as fmustate

DTYPE = [("a", "<f8"), ("b", "<i4")]


@pytest.mark.parametrize("array", [np.array([1.0, -2.5, 1e300]), np.array([[0.0, 3.0]]),
                                   np.array([(1.5, -2), (3.0, 7)], dtype=DTYPE), np.array([1 + 2j])],
                         ids=["plain", "2d", "record", "complex"])
def test_a_finite_array_over_nothing_yet_is_taken_as_the_states(array):
    got = fmustate.apply({"x": None}, {"x": array})
    assert got["x"].dtype == array.dtype and got["x"].tobytes() == array.tobytes()


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_non_finite_number_of_an_array_over_nothing_yet_is_refused_by_its_place(bad):
    plain = np.array([[1.0, 2.0], [3.0, bad]])
    with pytest.raises(fmustate.StateMismatch, match=r"^x\[1, 1\]: the state holds .*, not a finite number$"):
        fmustate.apply({"x": None}, {"x": plain})
    record = np.array([(1.5, -2), (bad, 7)], dtype=DTYPE)
    with pytest.raises(fmustate.StateMismatch, match=r"^x\['a'\]\[1\]: the state holds .*, not a finite number$"):
        fmustate.apply({"x": None}, {"x": record})


def test_only_the_instances_own_non_finite_values_at_their_places_pass():
    """The instance's array marks [1] with NaN and [2] with inf: the same marks pass, a NaN
    moved to [0], or a -inf where the instance holds inf, is refused."""
    def template():
        return {"x": np.array([0.0, math.nan, math.inf])}

    got = fmustate.apply(template(), {"x": np.array([5.0, math.nan, math.inf])})
    assert got["x"][0] == 5.0 and math.isnan(got["x"][1]) and got["x"][2] == math.inf
    number = r"(np\.float64\()?{}\)?"       # numpy 2 writes its scalars' repr with the type
    for place, value, state in ((0, "nan", [math.nan, 1.0, math.inf]), (2, "-inf", [1.0, math.nan, -math.inf])):
        refused = rf"^x\[{place}\]: the state holds {number.format(value)}, not a finite number$"
        with pytest.raises(fmustate.StateMismatch, match=refused):
            fmustate.apply(template(), {"x": np.array(state)})
