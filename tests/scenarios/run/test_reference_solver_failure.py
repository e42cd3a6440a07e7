"""The monolithic reference (scenarios/reference.py) when its ODE solve fails over an interval:
the run stops there with an error naming the plant and the interval, its rows ending at the
interval's start (issue 31, seed 3701's survivors 47 and 90)."""
import numpy as np
import pytest

from scenarios import reference
from scenarios.reference import reference_run

BENCH = "bench_circle_TCMDx"
STOP = 0.02
FAIL_AT = 3     # the solve of the fourth interval fails


def _failing_solve(monkeypatch, spoil):
    """``solve_ivp`` as in the product, the FAIL_AT-th call's result passed through ``spoil``."""
    real, calls = reference.solve_ivp, []

    def solve(*args, **kwargs):
        sol = real(*args, **kwargs)
        calls.append(args[1])
        if len(calls) == FAIL_AT + 1:
            spoil(sol)
        return sol

    monkeypatch.setattr(reference, "solve_ivp", solve)
    return calls


def _spoil_status(sol):
    sol.status, sol.message = -1, "Required step size is less than spacing between numbers."


def _spoil_first_state(sol):
    sol.y[0, -1] = np.nan       # the first plant coordinate at the interval's end; the last one stays finite


@pytest.mark.parametrize("spoil", [_spoil_status, _spoil_first_state], ids=["status", "nan_state"])
def test_a_failed_interval_ends_the_run_with_an_error_naming_it(monkeypatch, spoil):
    """Catches a solver failure reported with finite values (status != 0) or a non-finite state
    other than the last component at the interval's end going unnoticed: the run would carry on
    from a wrong or NaN state instead of stopping with an error naming the interval."""
    calls = _failing_solve(monkeypatch, spoil)
    run = reference_run(BENCH, stop_time=STOP)
    t0, t1 = calls[FAIL_AT]
    assert len(calls) == FAIL_AT + 1, "the run went on after the failed interval"
    assert run.error is not None and "solve_ivp failed over" in run.error
    assert f"[{t0:.6g}, {t1:.6g}] s" in run.error
    assert len(run.time) == FAIL_AT + 1 and run.time[-1] == pytest.approx(t0, abs=1e-15)
    assert all(np.all(np.isfinite(v)) for v in run.signals.values())


def test_without_a_failure_the_run_reaches_its_stop_time(monkeypatch):
    """Catches the check refusing a good interval (the failure test above passing for any run)."""
    calls = _failing_solve(monkeypatch, lambda sol: None)
    run = reference_run(BENCH, stop_time=STOP)
    assert run.error is None and run.time[-1] == pytest.approx(STOP, rel=1e-9)
    assert len(calls) == len(run.time) - 1
