"""The two tolerances of a system FMU's step rule (:func:`fmus.systemfmu.cores._steps_in`) hit
on both sides (issue 31, session 44: a constant's value never mattered where a test stays an
order of magnitude away from it).

A step size is a whole multiple n of the system's step h to 1e-9 relative (``math.isclose``:
relative to the larger of step size and n h); a communication point follows the last one to
1e-6 h absolute, at any time.  Points at 0.5 and 1.5 of each tolerance: the first accepted, the
second refused in the rule's words, so a tolerance doubled or halved is seen.
"""
from __future__ import annotations

import pytest

from fmus.systemfmu.cores import _steps_in

H = 2e-3


@pytest.mark.parametrize("n", [1, 3])
def test_a_step_size_within_a_billionth_of_n_h_is_n_steps_and_beyond_one_and_a_half_is_refused(n):
    """Catches the relative tolerance 1e-9 doubled (1.5e-9 taken) or cut (0.5e-9 refused)."""
    for side in (1, -1):
        assert _steps_in(0.5, 0.5, n * H * (1 + side * 0.5e-9), H, multiples=True) == n
        step = n * H * (1 + side * 1.5e-9)
        with pytest.raises(ValueError) as refused:
            _steps_in(0.5, 0.5, step, H, multiples=True)
        assert str(refused.value) == (f"step size {step!r} s at t = 0.5 s: this FMU steps its system at its "
                                      f"communication step; the step size must be a whole multiple of h = {H!r} s")


@pytest.mark.parametrize("time", [0.0, 0.25])
def test_a_communication_point_within_a_millionth_of_h_follows_and_beyond_one_and_a_half_does_not(time):
    """Catches the absolute tolerance 1e-6 h doubled (1.5e-6 h taken) or cut (0.5e-6 h refused),
    early or late, on either side of the expected point."""
    for side in (1, -1):
        assert _steps_in(time, time + side * 0.5e-6 * H, H, H, multiples=False) == 1
        point = time + side * 1.5e-6 * H
        with pytest.raises(ValueError) as refused:
            _steps_in(time, point, H, H, multiples=False)
        assert str(refused.value) == f"communication point t = {point!r} s does not follow the last one ({time!r} s)"
