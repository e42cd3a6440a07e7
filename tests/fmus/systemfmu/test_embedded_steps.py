"""The step-size rule of an FMU that runs a whole system (``fmus.embedded._steps_in``): the
number of communication steps h a ``doStep`` takes, and the refusal, by name and value, of
every step size that is not h (or a whole multiple of it), including the non-finite ones."""
from __future__ import annotations

import math

import pytest

from fmus.embedded import _steps_in

H = 2e-3            # not the 1 ms every scene uses


@pytest.mark.parametrize("multiple", [1, 2, 3, 250])
def test_a_whole_multiple_of_h_takes_that_many_steps(multiple):
    assert _steps_in(0.5, 0.5, multiple * H, H, multiples=True) == multiple
    if multiple > 1:
        with pytest.raises(ValueError, match=rf"step size {multiple * H!r} s at t = 0.5 s: .* must be h = {H!r} s"):
            _steps_in(0.5, 0.5, multiple * H, H, multiples=False)


@pytest.mark.parametrize("step_size", [math.inf, -math.inf, math.nan, 0.0, -H, 0.5 * H, 1.5 * H, H * (1 + 1e-6)])
def test_a_step_size_that_is_no_whole_multiple_of_h_is_refused_naming_it(step_size):
    with pytest.raises(ValueError) as refused:
        _steps_in(0.25, 0.25, step_size, H, multiples=True)
    assert str(refused.value) == (f"step size {step_size!r} s at t = 0.25 s: this FMU steps its system at its "
                                  f"communication step; the step size must be a whole multiple of h = {H!r} s")


def test_a_communication_point_must_follow_the_last_one():
    assert _steps_in(0.25, 0.25 + 1e-7 * H, H, H, multiples=False) == 1       # within 1e-6 h
    with pytest.raises(ValueError, match=r"communication point t = 0.2520000000000001 s does not follow the last one \(0.25 s\)"):
        _steps_in(0.25, 0.25 + H + 1e-16, H, H, multiples=False)


@pytest.mark.parametrize("time", [0.0, 0.25, 100.0])
def test_a_communication_point_is_matched_within_a_millionth_of_h_at_any_time(time):
    """The tolerance is 1e-6 h whatever the time: at t = 0 a point off by 1e-7 h follows; at
    any t one off by 1e-5 h does not (a tolerance relative to t would accept it late in a run,
    and refuse anything but an exact match at t = 0)."""
    assert _steps_in(time, time + 1e-7 * H, H, H, multiples=False) == 1
    with pytest.raises(ValueError, match="does not follow the last one"):
        _steps_in(time, time + 1e-5 * H, H, H, multiples=False)
