"""scenarios/batch/engine.py's ``run_tasks`` on a one-worker cluster of threads: what it hands
back and calls back, read exactly: the fractions given to ``progress`` (k / n after the k-th
task, 1 for no task), ``on_result`` once per task with the metrics returned under that task's
key, and the keys' check (issue 31: seed 3501's survivor [64], the progress fraction given as a
count; the engine's other runs are of the slow kind)."""
from __future__ import annotations

from dataclasses import replace

import pytest

from scenarios.batch.engine import Task, open_client, run_tasks
from scenarios.scenes import get_scene


def _short(stop=0.01):
    scene = get_scene("bench_circle_PDq")
    return replace(scene, system=replace(scene.system, stop_time=stop))


@pytest.fixture(scope="module")
def client():
    with open_client(workers=1, processes=False) as c:
        yield c


def test_progress_is_the_fraction_of_tasks_done_and_each_result_is_called_back_once(client, tmp_path):
    """Three tasks that cannot start (each output folder is under a file, named in its error):
    ``progress`` gets 1/3, 2/3, 1 in that order, ``on_result`` each task once with the metrics
    returned under its key.  Catches the fraction given as a count or over the wrong total
    (3501's [64]), a result called back twice or under another task's key, and a failed task
    missing from the results."""
    blocked = tmp_path / "file"
    blocked.write_text("")
    tasks = [Task(key, _short(), out_dir=str(blocked / key)) for key in ("a", "b", "c")]
    fractions, called = [], []
    results = run_tasks(tasks, client=client, progress=fractions.append,
                        on_result=lambda task, metrics: called.append((task.key, metrics)))
    assert fractions == [1 / 3, 2 / 3, 1.0]
    assert sorted(key for key, _ in called) == ["a", "b", "c"] and results == dict(called)
    for key, metrics in results.items():
        assert metrics["outcome"] == "failed" and metrics["scene"] == "bench_circle_PDq"
        assert f"output directory {blocked / key} is not writable" in metrics["error"]["message"]


def test_no_task_is_done_at_once_and_repeated_keys_are_refused(client):
    """Catches an empty list waiting on the cluster or reporting no progress, and two tasks
    under one key (the second's row would replace the first's) accepted."""
    fractions = []
    assert run_tasks([], client=client, progress=fractions.append) == {} and fractions == [1.0]
    with pytest.raises(ValueError, match="task keys must be unique"):
        run_tasks([Task("a", _short()), Task("a", _short())], client=client)
