"""plant/integrators.py's dopri5 work limit at its edges (issue 31, training sweep s44: compare
mutants at integrators.py:84 and :90).

``max_evaluations`` bounds the calls of f: a step attempt (6 calls, after the first one) that
would *exceed* it is not begun.  So a limit equal to the calls an unbounded run makes gives
that run, unchanged; 7 (one attempt) is the least that lets any step be tried, and 6 is refused
before any.
"""
from __future__ import annotations

import numpy as np
import pytest

from plant.integrators import WorkLimitError, dopri5

A = np.array([[0.0, 1.0], [-4.0, -0.2]])
Y0 = np.array([1.0, 0.0])


def f(y):
    return A @ y


@pytest.mark.parametrize("rtol, dt", [(1e-10, 2.0), (1e-1, 1e-3)])
def test_a_limit_of_exactly_the_calls_an_unbounded_run_makes_gives_that_run(rtol, dt):
    """The unbounded run's (y, h_next, steps, calls) come back with max_evaluations = its calls
    (no refusal, the same numbers); one call fewer refuses."""
    free = dopri5(f, Y0, dt, rtol=rtol, atol=rtol * 1e-3)
    bounded = dopri5(f, Y0, dt, rtol=rtol, atol=rtol * 1e-3, max_evaluations=free[3])
    np.testing.assert_array_equal(bounded[0], free[0])
    assert bounded[1:] == free[1:]
    with pytest.raises(WorkLimitError):
        dopri5(f, Y0, dt, rtol=rtol, atol=rtol * 1e-3, max_evaluations=free[3] - 1)


def test_seven_calls_allow_one_attempt_and_six_none():
    """A short step a loose tolerance accepts at once takes 7 calls (the first derivative and one
    attempt's six): a limit of 7 takes it, 6 is refused before any call, at t + 0."""
    y, _, steps, calls = dopri5(f, Y0, 1e-3, rtol=1e-1, atol=1e-4, max_evaluations=7)
    assert (steps, calls) == (1, 7)
    np.testing.assert_array_equal(y, dopri5(f, Y0, 1e-3, rtol=1e-1, atol=1e-4)[0])
    with pytest.raises(WorkLimitError) as refused:
        dopri5(f, Y0, 1e-3, rtol=1e-1, atol=1e-4, max_evaluations=6)
    assert (refused.value.evaluations, refused.value.limit, refused.value.reached) == (0, 6, 0.0)
