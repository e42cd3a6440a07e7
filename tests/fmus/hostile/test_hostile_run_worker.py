"""fmus/hostile/cases.py's worker processes, for real but on FMUs that are not there (so each
worker fails on its first case at once): a worker that ends before a case's result is a
"crash" with its exit status, the next cases go to a new worker, and a worker that sends no
result within the case timeout is a "hang", killed (issue 31: these verdicts ran only in the
slow campaign, where nothing crashes or hangs)."""
from __future__ import annotations

import time

from fmus.hostile.cases import _run_worker, run_cases

CASE = {"model": "M", "instance_name": "i", "logging": False, "start_time": 0.0, "parameters": [], "ops": []}
#: An FMU folder with no modelDescription.xml: the worker raises on reading it and exits 1.
NOWHERE = {"M": "/nonexistent/parcosim-hostile-fmu"}


def test_a_worker_that_ends_before_the_result_is_a_crash_and_the_rest_go_to_new_workers():
    """Two cases, two a worker: each crashes its worker, so two workers run one case each
    and each case is a crash naming exit status 1.  Catches the cases after a crash
    dropped, given to the dead worker or repeated, and a crash reported as a hang or fatal."""
    cases = [{**CASE, "seed": k} for k in range(2)]
    seen = []
    results = run_cases(cases, NOWHERE, batch=2, case_timeout=60.0, progress=seen.append)
    assert [r.case["seed"] for r in results] == [0, 1] and seen == results
    assert [(r.outcome, r.problems) for r in results] == [("crash", ["worker exit status 1"])] * 2
    assert all(0.0 <= r.seconds < 60.0 for r in results)


def test_a_worker_silent_past_the_case_timeout_is_a_hang_and_is_killed():
    """A timeout shorter than a worker takes to start: the case is a hang naming the timeout,
    found within about the timeout, not after the worker ended.  Catches the deadline
    computed the wrong way (select waiting for ever) or a hang taken for a crash."""
    start = time.monotonic()
    [result] = _run_worker([{**CASE, "seed": 0}], NOWHERE, 0.001)
    assert time.monotonic() - start < 5.0
    assert (result.outcome, result.problems) == ("hang", ["no result within 0.001 s"])
    assert result.seconds < 5.0
