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


#: A stand-in worker (run in place of ``python -m fmus.hostile.worker``): it answers its cases in
#: the order given, several results in one write and one result split over two writes, as a pipe
#: may deliver them; a case whose seed is 9 is "fatal" and the worker stops there.
FAKE_WORKER = r'''
import json, os, sys, time
cases = json.loads(sys.stdin.read())["cases"]
fd = int(os.environ["HOSTILE_RESULT_FD"])
lines = [json.dumps({"outcome": "fatal" if c["seed"] == 9 else ["ok", "refused"][c["seed"] % 2],
                     "statuses": [c["seed"], 0], "problems": [f"p{c['seed']}"], "seconds": 0.5 + c["seed"]})
         + "\n" for c in cases]
text = "".join(lines).encode()
half = len(lines[0]) + len(lines[1]) // 2 if len(lines) > 1 else len(text)
os.write(fd, text[:half]); time.sleep(0.2); os.write(fd, text[half:])
time.sleep(0.2)
'''


def _with_fake_worker(monkeypatch):
    import subprocess
    import sys

    real = subprocess.Popen
    monkeypatch.setattr(subprocess, "Popen", lambda args, **kw: real([sys.executable, "-c", FAKE_WORKER], **kw))


def test_results_are_read_line_by_line_whatever_the_pipe_delivers_and_a_fatal_one_ends_the_worker(monkeypatch):
    """Three results, two in the first read and the second cut in half: each case gets its own
    outcome, statuses, problems and seconds in order; with a "fatal" second case the third
    is not taken from that worker.  Catches a result line split wrongly, a buffer not carried
    over to the next read, or a fatal case read past."""
    _with_fake_worker(monkeypatch)
    cases = [{**CASE, "seed": k} for k in (0, 1, 2)]
    results = _run_worker(cases, NOWHERE, 30.0)
    assert [(r.case["seed"], r.outcome, r.statuses, r.problems, r.seconds) for r in results] == [
        (0, "ok", [0, 0], ["p0"], 0.5), (1, "refused", [1, 0], ["p1"], 1.5), (2, "ok", [2, 0], ["p2"], 2.5)]
    results = _run_worker([{**CASE, "seed": k} for k in (0, 9, 2)], NOWHERE, 30.0)
    assert [(r.case["seed"], r.outcome) for r in results] == [(0, "ok"), (9, "fatal")]


def test_a_worker_runs_this_trees_fmus_from_any_folder_before_an_inherited_python_path(monkeypatch, tmp_path):
    """The worker imports the ``fmus`` of the tree the campaign runs from, whatever the current
    folder and ``PYTHONPATH`` (a mutation run's worktree, a checkout beside an installed copy):
    from a foreign folder, with ``PYTHONPATH`` naming a decoy ``fmus`` that exits with status 42,
    the worker still fails as this tree's does on a missing FMU (status 1). Catches the tree's
    root left out of the worker's ``PYTHONPATH`` (the decoy, or an installed copy, runs)."""
    decoy = tmp_path / "decoy" / "fmus"
    decoy.mkdir(parents=True)
    (decoy / "__init__.py").write_text("import os\nos._exit(42)\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)      # ``python -m`` looks in the current folder first
    monkeypatch.setenv("PYTHONPATH", str(decoy.parent))
    [result] = _run_worker([{**CASE, "seed": 0}], NOWHERE, 60.0)
    assert (result.outcome, result.problems) == ("crash", ["worker exit status 1"])
