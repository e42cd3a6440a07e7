"""Property-based: every FMU through fmpy under random, hostile and careless use (issue 13).

Cases come from :func:`fmus.hostile.cases.make_case` (random parameters, inputs, step sizes,
call orders and strings) and run in worker subprocesses (:func:`fmus.hostile.cases.run_cases`),
30 a worker, so that a crash of the importing process fails a test instead of ending the
session.  Hypothesis draws the cases' seeds,
derandomised: CI runs the same 30 cases per FMU every time (about a minute in all).

Properties (docs/extremes.md, "The FMI calls under hostile use"): no crash, no hang, no call
over 10 s, every status OK, Warning, Discard or Error (never Fatal), no non-finite Real
output after an fmi2OK step, a refused step leaves a message in ``error`` naming something.

Sets that FMI 2.0 wants refused with fmi2Error (an output, a fixed parameter after
initialisation, an unknown value reference) return fmi2Fatal with pythonfmu's own binary:
those cases run only when the FMU's binary is parcosim's FMI wrapper (it exports
``parcosimFmi2WrapperVersion``).
"""
from __future__ import annotations

import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fmus.export.build import SLAVES
from fmus.slave.base import WRAPPER_SYMBOL
from fmus.hostile import cases as hostile

pytestmark = [pytest.mark.slow, pytest.mark.fmu]

CASES_PER_FMU = 30
#: A batch of consecutive case seeds (derandomised with one example: 0 ... 29; each FMU mixes
#: its name into the seed).
SEEDS = st.integers(0, 2 ** 31 - 1).map(lambda base: [base + i for i in range(CASES_PER_FMU)])
CI = settings(max_examples=1, derandomize=True, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))


@pytest.fixture(scope="session")
def extracted(built_fmus, tmp_path_factory):
    """Model -> its FMU extracted once."""
    return hostile.extract_fmus(built_fmus, tmp_path_factory.mktemp("hostile") / "fmus")


@pytest.fixture(scope="session")
def wrapper(extracted):
    """Model -> whether its binary is parcosim's FMI wrapper."""
    return {model: hostile.wrapper_is_ours(path, model) for model, path in extracted.items()}


def failures(results) -> list:
    """The cases that broke a property, with what to replay them."""
    bad = []
    for r in results:
        if r.outcome not in ("ok", "refused") or r.problems:
            bad.append(f"{r.outcome}: {r.problems} -- case {json.dumps(r.case)[:600]} -- "
                       f"last calls {r.statuses[-4:]}")
    return bad


def run(model, seeds, extracted, wrapper, kinds):
    cases = hostile.cases_for(model, extracted[model], seeds, wrapper=wrapper, kinds=kinds)
    return hostile.run_cases(cases, extracted, batch=CASES_PER_FMU)


@pytest.mark.parametrize("model", list(SLAVES))
@CI
@given(seeds=SEEDS)
def test_no_crash_no_fatal_no_nan_under_hostile_use(model, seeds, extracted, wrapper):
    """Catches an FMU that crashes, returns fmi2Fatal, hangs, gives a NaN output after an accepted step, or
    breaks an FMI rule under random hostile call sequences."""
    kinds = [k for k in hostile.KINDS if k not in hostile.WRAPPER_KINDS]
    results = run(model, seeds, extracted, wrapper[model], kinds)
    assert len(results) == CASES_PER_FMU
    assert not failures(results), "\n".join(failures(results))
    assert {r.case["kind"] for r in results} == set(kinds)
    assert any(r.outcome == "ok" for r in results) and any(r.outcome == "refused" for r in results)


@pytest.mark.parametrize("model", list(SLAVES))
@CI
@given(seeds=SEEDS)
def test_refused_sets_states_start_times_and_call_orders_are_fmi2error_not_fatal(model, seeds, extracted, wrapper):
    """Sets FMI 2.0 refuses, bytes that are not this FMU's state (random, truncated, altered,
    another FMU's, the pickle exploit: refused, no command run), start times that are not
    usable and calls out of FMI 2.0's order give fmi2Error (an instantiation with another
    GUID gives no instance); a forged state that is taken steps cleanly."""
    if not wrapper[model]:
        pytest.skip(f"{model}.fmu has pythonfmu's binary (no {WRAPPER_SYMBOL}): a refused set (FmiError) is "
                    "fmi2Fatal there; parcosim's FMI wrapper makes it fmi2Error")
    results = run(model, seeds, extracted, True, list(hostile.WRAPPER_KINDS))
    assert not failures(results), "\n".join(failures(results))
    assert all(any(s[1] == "Error" for s in r.statuses) for r in results if r.case["kind"] == "sets"
               and any(op[0] == "set_vr" for op in r.case["ops"]))
    for r in results:
        variants = [op[1] for op in r.case["ops"] if op[0] == "state_bytes"]
        if r.case["kind"] == "state" and variants[0] not in ("forged", "foreign"):
            assert [s[1] for s in r.statuses if s[0].startswith("deSerializeFMUstate")] == ["Error"], r.statuses


def test_the_worker_reports_a_crash_and_goes_on(extracted):
    """A case that kills its worker is a crash; the next case runs in a new worker."""
    cases = hostile.cases_for("Trajectory", extracted["Trajectory"], [1, 2, 3], kinds=["inputs"])
    cases[1]["ops"].insert(0, ["crash"])
    results = hostile.run_cases(cases, extracted)
    assert [r.outcome for r in results] == ["ok", "crash", "ok"]
    assert "signal" in results[1].problems[0]
