"""fmus/ssp/libcosim.py's reading of an observer's samples at the edge of libcosim's count
(issue 31, training sweep s44: compare mutant at libcosim.py:166).

``cosim_observer_slave_get_real_samples`` returns the number of samples it wrote, or a negative
number on an error: zero samples (a signal observed before any step was recorded) is an empty
series, not an error; a negative count is refused with libcosim's last error message.  The C
function is replaced here by one returning a given count (libcosim need not run).
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

libcosimpy_internal = pytest.importorskip("libcosimpy._internal")

from fmus.ssp import libcosim  # noqa: E402


def _with_count(monkeypatch, n):
    def wrap_function(lib, funcname, argtypes, restype):
        assert funcname == "cosim_observer_slave_get_real_samples"

        def get(observer, slave, reference, start, count, values, steps, times):
            for k in range(max(n, 0)):
                values[k], times[k] = 0.5 * k, 1000 * k
            return n
        return get
    monkeypatch.setattr(libcosimpy_internal, "wrap_function", wrap_function)
    monkeypatch.setattr(libcosimpy_internal, "libcosimc", lambda: None)
    monkeypatch.setattr(libcosimpy_internal, "get_last_error_message", lambda: "no such slave")
    return SimpleNamespace(ptr=lambda: None)


@pytest.mark.parametrize("n", [0, 1, 3])
def test_a_count_of_zero_or_more_is_that_many_samples(monkeypatch, n):
    """0 samples: two empty arrays; 1 or 3: the values and times libcosim wrote, in order."""
    values, times = libcosim._real_samples(_with_count(monkeypatch, n), 0, 0, 4)
    np.testing.assert_array_equal(values, [0.5 * k for k in range(n)])
    np.testing.assert_array_equal(times, [1000 * k for k in range(n)])
    assert times.dtype == np.int64


def test_a_negative_count_is_refused_with_libcosims_message(monkeypatch):
    with pytest.raises(RuntimeError, match=r"^libcosim has no samples: no such slave$"):
        libcosim._real_samples(_with_count(monkeypatch, -1), 0, 0, 4)


@pytest.mark.parametrize("step_size, step_ns", [(1e-9, 1), (2e-9, 2), (1e-3, 1_000_000)])
def test_a_step_of_one_nanosecond_or_a_whole_number_of_them_is_taken(monkeypatch, step_size, step_ns):
    """libcosim's time unit is 1 ns: a step of exactly one (the least) is taken, as its count."""
    monkeypatch.setattr(libcosim, "read_ssp_experiment", lambda path: (None, 2.0, 1e-3))
    assert libcosim._experiment("p.ssp", None, None, step_size) == (2.0, step_size, step_ns)


@pytest.mark.parametrize("step_size, words", [
    (0.0, "step_size = 0.0 must be > 0"),
    (-1e-3, "step_size = -0.001 must be > 0"),
    (0.4e-9, "step_size = 4e-10 s is no whole number of nanoseconds (libcosim's time unit)"),
    (1.5e-9, "step_size = 1.5e-09 s is no whole number of nanoseconds (libcosim's time unit)"),
])
def test_a_step_of_zero_or_less_or_of_no_whole_number_of_nanoseconds_is_refused(monkeypatch, step_size, words):
    """Zero and below refused as not positive; 0.4 ns rounds to no nanosecond at all and 1.5 ns
    to a count it is not: refused naming the step."""
    monkeypatch.setattr(libcosim, "read_ssp_experiment", lambda path: (None, 2.0, 1e-3))
    with pytest.raises(ValueError, match=rf"^{words}$".replace("(", r"\(").replace(")", r"\)")):
        libcosim._experiment("p.ssp", None, None, step_size)
