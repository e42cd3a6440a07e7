"""The monolithic reference hands solve_ivp the tolerances and method it was asked for
(scenarios/reference.py ``reference_run``: "rtol, atol: tolerances of solve_ivp over each
sample interval"), and by default those docs/reference.md states (DOP853, rtol 1e-10,
atol 1e-13).  solve_ivp is spied on (the real one still runs), on a 5 ms run of the bench
circle (training sample 4341 [18]: rtol replaced by atol in the solver's arguments; a tighter
rtol changes no result a test reads, so only the call itself shows it)."""
from __future__ import annotations

import re
from dataclasses import replace

import pytest

from scenarios import reference
from scenarios.scenes.catalogue import get_scene
from tests.support.paths import ROOT

STOP = 0.005


@pytest.fixture
def calls(monkeypatch):
    seen = []
    real = reference.solve_ivp

    def spy(fun, span, y0, **kwargs):
        seen.append((tuple(span), kwargs))
        return real(fun, span, y0, **kwargs)

    monkeypatch.setattr(reference, "solve_ivp", spy)
    return seen


def _system():
    return replace(get_scene("bench_circle_TCMDx").system, stop_time=STOP)


def test_each_interval_is_integrated_with_the_given_rtol_atol_and_method(calls):
    """rtol 1e-7, atol 1e-9 and RK45 (none the defaults) reach every solve_ivp call, one call per
    sample interval [t_k, t_k + h]; the result records the same three.  Catches rtol and atol
    swapped or one given for the other, the method not passed, and intervals of another length."""
    system = _system()
    ref = reference.reference_run(system, rtol=1e-7, atol=1e-9, method="RK45")
    assert ref.completed and (ref.rtol, ref.atol, ref.method) == (1e-7, 1e-9, "RK45")
    steps = round(STOP / system.step)
    assert len(calls) == steps
    for k, (span, kwargs) in enumerate(calls):
        assert (kwargs["rtol"], kwargs["atol"], kwargs["method"]) == (1e-7, 1e-9, "RK45")
        assert span[0] == pytest.approx(k * system.step, abs=1e-15)
        assert span[1] - span[0] == pytest.approx(system.step, rel=1e-12)


def test_the_default_solver_is_the_documents(calls):
    """Without arguments: DOP853 at rtol 1e-10 and atol 1e-13, the numbers docs/reference.md
    states and measured its convergence at.  Catches a default changed in the code alone."""
    text = (ROOT / "docs" / "reference.md").read_text()
    found = re.search(r"\(DOP853, rtol ([0-9e.-]+), atol ([0-9e.-]+)", text)
    assert found, "docs/reference.md no longer states the default solver"
    ref = reference.reference_run(_system())
    expected = (float(found.group(1)), float(found.group(2)), "DOP853")
    assert (ref.rtol, ref.atol, ref.method) == expected
    assert {(kw["rtol"], kw["atol"], kw["method"]) for _, kw in calls} == {expected}


def test_a_failed_interval_is_refused_naming_the_plant_the_interval_and_the_solvers_message(monkeypatch):
    """The third interval's solve reports failure: the run's error is, word for word, the master
    loop's refusal of the plant's step at t, then the plant's instance name, the interval
    [t, t + h] to 6 digits and solve_ivp's own message.  Catches the
    interval's end or start of another time, the instance or the message left out."""
    real, spans = reference.solve_ivp, []

    def failing(fun, span, y0, **kwargs):
        sol = real(fun, span, y0, **kwargs)
        spans.append(tuple(span))
        if len(spans) == 3:
            sol.status, sol.message = -1, "made-up failure"
        return sol

    monkeypatch.setattr(reference, "solve_ivp", failing)
    ref = reference.reference_run(_system())
    t0, t1 = spans[2]
    assert t0 == pytest.approx(0.002, abs=1e-15) and t1 == pytest.approx(0.003, abs=1e-15)
    # The master's loop names the refusing instance and the step's start before the reference's text.
    assert ref.error == (f"plant refused the step from t = {t0:g} s: "
                         f"plant: solve_ivp failed over [{t0:.6g}, {t1:.6g}] s: made-up failure")
    assert not ref.completed
