"""``simulate``'s defaults and argument checks (fmus/cosim/master.py): in process, Gauss-Seidel,
no retry unless asked; a coupling, mode or retry count off the documented ones refused by
name before anything runs, and retry_substeps = 2, the least, accepted."""
from __future__ import annotations

import pytest

from fmus.cosim.master import simulate
from fmus.cosim.system import Component, System

SYSTEM = System((Component("traj", "Trajectory"),), (), ("traj.x_d",), stop_time=0.005)


def test_a_run_without_options_is_in_process_gauss_seidel_without_retries():
    result = simulate(SYSTEM)
    assert result.completed, result.error
    assert (result.mode, result.coupling) == ("inprocess", "gauss-seidel")
    assert "retried" not in result.extra and len(result["traj.x_d"]) == 6


def test_the_least_retry_count_is_accepted():
    result = simulate(SYSTEM, retry_substeps=2)
    assert result.completed, result.error


@pytest.mark.parametrize("options, message", [
    ({"coupling": "gauss_seidel"}, "coupling = 'gauss_seidel'; valid: gauss-seidel, jacobi"),
    ({"mode": "process"}, "mode = 'process'; valid: fmu, inprocess, compiled"),
    ({"retry_substeps": 1}, "retry_substeps = 1 must be an integer >= 2 (or None: no retry)"),
    ({"retry_substeps": 2.0}, "retry_substeps = 2.0 must be an integer >= 2 (or None: no retry)"),
])
def test_an_option_off_the_documented_ones_is_refused_naming_it(options, message):
    with pytest.raises(ValueError) as refused:
        simulate(SYSTEM, **options)
    assert str(refused.value) == message
