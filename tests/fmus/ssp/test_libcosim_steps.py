"""libcosim's time unit is the nanosecond: ``fmus.libcosim_runner._experiment`` turns a step
size into whole nanoseconds and refuses, by value, one that is not a whole number of them
(the package's own experiment is stubbed: nothing is run)."""
from __future__ import annotations

import pytest

from fmus import libcosim_runner


@pytest.fixture
def experiment(monkeypatch):
    monkeypatch.setattr(libcosim_runner, "read_ssp_experiment", lambda path: (0.0, 1.0, 1e-3))
    return lambda stop, step: libcosim_runner._experiment("package.ssp", None, stop, step)


def test_a_step_of_whole_nanoseconds_is_taken_as_their_count(experiment):
    """Catches a step size converted to nanoseconds by truncation (3e-9 s as 2 ns) or the package's own
    experiment ignored."""
    assert experiment(2.0, 2e-3) == (2.0, 2e-3, 2_000_000)
    assert experiment(None, None) == (1.0, 1e-3, 1_000_000)          # the package's own experiment
    assert experiment(1.0, 3e-9) == (1.0, 3e-9, 3)


@pytest.mark.parametrize("step", [1.5e-9, 2.5e-9, 0.4e-9])
def test_a_step_that_is_no_whole_number_of_nanoseconds_is_refused_naming_it(experiment, step):
    with pytest.raises(ValueError) as refused:
        experiment(1.0, step)
    assert str(refused.value) == f"step_size = {step!r} s is no whole number of nanoseconds (libcosim's time unit)"
