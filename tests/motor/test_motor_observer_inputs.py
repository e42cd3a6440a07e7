"""CurrentObserver.estimate given inputs ctypes does not take as doubles (motor/observer.py's
converting path, motor/kernel.call): 0-d numpy arrays give the estimate of the same floats, on a
first call, at a new step length (the coefficients prepared on the way) and for each input in
its place; a text is refused naming the input it was given for, and nothing is kept."""
from __future__ import annotations

import numpy as np
import pytest

from motor import CurrentObserver, motor1
from motor._checks import BadValue

INPUTS = ("v", "omega", "h")
CALLS = [(6.0, 40.0, 1e-3), (-3.0, 12.5, 2e-3), (1.5, -7.0, 5e-4)]     # each call a new step length


@pytest.mark.parametrize("kind", ["static", "dynamic"])
def test_0d_arrays_give_the_estimates_of_the_same_floats_through_new_step_lengths(kind):
    """Catches the converting path calling the kernel with its inputs in another order, without
    preparing a new step length's coefficients, or with one input left out."""
    floats, arrays = CurrentObserver(motor1, kind), CurrentObserver(motor1, kind)
    for call in CALLS:
        expected = floats.estimate(*call)
        assert arrays.estimate(*(np.array(x) for x in call)) == expected
        assert arrays.i_hat == floats.i_hat


@pytest.mark.parametrize("position", range(3))
def test_one_array_input_in_its_place_gives_the_float_estimate(position):
    """Catches the conversion applied to one input only or an input taken from another place."""
    floats, mixed = CurrentObserver(motor1, "dynamic"), CurrentObserver(motor1, "dynamic")
    for call in CALLS:
        given = [np.array(x) if k == position else x for k, x in enumerate(call)]
        assert mixed.estimate(*given) == floats.estimate(*call)


@pytest.mark.parametrize("position", range(3))
def test_a_text_input_is_refused_naming_that_input_and_its_value_and_nothing_is_kept(position):
    """Catches a refusal that names another input than the one given as text, or an estimate
    changed by the refused call."""
    observer = CurrentObserver(motor1, "dynamic")
    before = observer.estimate(*CALLS[0])
    given = list(CALLS[1])
    given[position] = "fast"
    with pytest.raises(BadValue) as refused:
        observer.estimate(*given)
    assert str(refused.value) == f"{INPUTS[position]} must be a finite number, got 'fast'"
    assert observer.i_hat == before
