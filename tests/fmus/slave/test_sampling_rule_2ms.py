"""fmus/slave/sampling.py's step-size rule at a sample time of 2 ms (its tests elsewhere use 1 ms):
which steps divide T (whole n, 1e-9 relative), the phase's bound from n, a step changed within
a period refused naming h, T, the sub-step and t (issue 31, pattern 1)."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from fmus.slave.sampling import check_period_change, check_phase, checked_substeps, substeps_of

T = 2e-3


@pytest.mark.parametrize("h, n", [(2e-3, 1), (1e-3, 2), (5e-4, 4), (T / 3, 3), (T / 7, 7), (2e-4, 10),
                                  (5e-4 * (1 + 5e-10), 4)])
def test_a_step_dividing_2ms_gives_its_whole_number_of_sub_steps(h, n):
    """Catches the sub-step count of a 2 ms sample time rounded down (or refused) for steps that divide it
    up to rounding, such as T/3 or 5e-4 (1 + 5e-10)."""
    assert substeps_of(T, h) == n


@pytest.mark.parametrize("h", [3e-4, 4e-3, 1.5e-3, 5e-4 * (1 + 1e-8), 7e-4])
def test_a_step_not_dividing_2ms_or_longer_is_none(h):
    """Catches T and h swapped (4 ms would divide), the tolerance loosened to 1e-8."""
    assert substeps_of(T, h) is None


def _slave(phase=0):
    return SimpleNamespace(T=T, sample_phase=phase, step_size_message=lambda t, h, why: f"h = {h!r} at {t!r}: {why}")


def test_the_phase_must_be_below_n_of_the_step():
    """Phase 3 with h = T/4 (n = 4) is accepted; with h = T/2 (n = 2) refused naming [0, 2);
    a phase that is not an int is refused too."""
    assert checked_substeps(_slave(3), 0.0, 5e-4) == 4
    with pytest.raises(ValueError, match=r"sample_phase = 3 must be a whole number in \[0, T / h\) = \[0, 2\) for "
                                         r"the step size h = 0.001 s at t = 0.5 s \(T = 0.002 s\)"):
        checked_substeps(_slave(3), 0.5, 1e-3)
    with pytest.raises(ValueError, match=r"sample_phase = 1.0 must be a whole number"):
        check_phase(_slave(1.0), 0.0, 5e-4, 4)
    with pytest.raises(ValueError, match=r"h = 0.0003 at 0.25: does not divide the sample time T = 0.002 s"):
        checked_substeps(_slave(), 0.25, 3e-4)


def test_the_step_changes_only_at_a_period_start():
    """Sub-step 0 may change n (4 -> 2); sub-step 1 of 4 may not, and the message names h, t,
    T, the sub-step and the steps counted.  Catches the comparison of n made with the wrong
    count, or at every sub-step."""
    check_period_change(_slave(), 0.004, 1e-3, 2, 4, 0)
    check_period_change(_slave(), 0.0045, 5e-4, 4, 4, 1)
    with pytest.raises(ValueError, match=r"step size h = 0.001 s at t = 0.0045 s changes the step within a sample "
                                         r"period \(T = 0.002 s, sub-step 1 of 4, steps of 0.0005 s\)"):
        check_period_change(_slave(), 0.0045, 1e-3, 2, 4, 1)
