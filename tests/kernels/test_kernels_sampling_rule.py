"""The sub-step counting rule of sampled components (kernels/src/pc_sampling.c, documented in
pc_sampling.h and docs/master.md): h divides T when T / h is within 1e-9 relative of a whole
number n >= 1; the period's sub-step counter wraps to 0 after n steps; n may change only at a
period's start.  Checked case by case against that text, on both sides of each limit."""
from __future__ import annotations

import ctypes
import math

import pytest

import kernels
from fmus.slave.sampling import SAMPLE_TOLERANCE

_d = ctypes.c_double
substeps = kernels.function("pc_sampling_substeps", _d, _d, _d)
changes_period = kernels.function("pc_sampling_changes_period", ctypes.c_int, _d, _d, _d)
samples = kernels.function("pc_sampling_samples", ctypes.c_int, _d, _d)
next_substep = kernels.function("pc_sampling_next", _d, _d, _d)


def test_the_tolerance_is_the_documented_one_in_a_billion():
    assert SAMPLE_TOLERANCE == 1e-9


@pytest.mark.parametrize("T, h, n", [
    (1e-3, 1e-3, 1.0),            # n = 1: the smallest whole number accepted
    (1e-2, 1e-3, 10.0),
    (1.0, 0.25, 4.0),
    (1e-3, 2e-3, 0.0),            # T / h = 1/2 rounds (half to even) to 0: refused, not n = 1
    (1e-3, 3e-3, 0.0),            # 1/3 rounds to 0
    (1.5, 1.0, 0.0),              # 1.5 -> 2, 0.5 away: not whole
    (2.5, 1.0, 0.0),
    (1.0, math.inf, 0.0), (math.nan, 1.0, 0.0),
])
def test_h_divides_t_only_a_whole_number_of_at_least_one_times(T, h, n):
    assert substeps(T, h) == n


@pytest.mark.parametrize("n", [1.0, 10.0, 1000.0])
def test_the_divisibility_tolerance_is_relative_to_n(n):
    """T / h off a whole number n by 0.5e-9 n is accepted as n, by 2e-9 n refused (0): the
    tolerance scales with n, on either side."""
    h = 0.25
    for off, expected in ((0.5e-9, n), (-0.5e-9, n), (2e-9, 0.0), (-2e-9, 0.0)):
        assert substeps(n * h * (1.0 + off), h) == expected, (n, off)


def test_n_may_change_only_at_a_periods_start():
    """changes_period(substep, counted, n): refused only past the start (substep != 0) with an n
    other than the counted one."""
    assert changes_period(0.0, 4.0, 5.0) == 0
    assert changes_period(1.0, 4.0, 4.0) == 0
    assert changes_period(1.0, 4.0, 5.0) == 1
    assert changes_period(3.0, 4.0, 2.0) == 1


def test_the_sample_is_taken_on_its_phase_and_the_counter_wraps_after_n():
    assert [samples(k, 2.0) for k in (0.0, 1.0, 2.0, 3.0)] == [0, 0, 1, 0]
    assert [next_substep(k, 4.0) for k in (0.0, 1.0, 2.0, 3.0)] == [1.0, 2.0, 3.0, 0.0]
    assert next_substep(0.0, 1.0) == 0.0          # n = 1: every step starts a period
