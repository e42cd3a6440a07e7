"""fmus/ssp/run.py's experiment (fmpy's and ecos' runs of an SSP package) at the edge of its
step size (issue 31, training sweep s44: compare mutant at run.py:85, ``step_size > 0``).

The step size given, or else the package's, must be positive: the least positive double is
taken as it is, zero, -0.0, a negative step and NaN are refused naming the value.  The package's
experiment is replaced here (no package is read).
"""
from __future__ import annotations

import math

import pytest

from fmus.ssp import run


@pytest.fixture(autouse=True)
def _package(monkeypatch):
    monkeypatch.setattr(run, "read_ssp_experiment", lambda path: (0.0, 2.0, 1e-3))


@pytest.mark.parametrize("step_size", [5e-324, 1e-3])
def test_a_positive_step_is_taken_as_given(step_size):
    assert run._experiment("p.ssp", None, step_size) == (2.0, step_size)


def test_without_a_step_the_packages_is_taken():
    assert run._experiment("p.ssp", 1.5, None) == (1.5, 1e-3)


@pytest.mark.parametrize("step_size", [0.0, -0.0, -1e-3, math.nan])
def test_a_step_of_zero_or_less_or_not_a_number_is_refused_naming_it(step_size):
    with pytest.raises(ValueError, match=rf"^step_size = {step_size!r} must be > 0$"):
        run._experiment("p.ssp", None, step_size)
