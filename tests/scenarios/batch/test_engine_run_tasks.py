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


def _raising(task):
    raise MemoryError(f"worker of {task.key} ran out of memory")


def test_a_task_whose_worker_raises_is_a_failed_row_naming_the_exception(client, monkeypatch):
    """A worker failure (the task's function itself raising, as a KilledWorker does): that task's
    row has no metric, the scene's name, outcome ``failed`` and the exception's type and message
    as its error; the other tasks are unaffected.  Catches a raising task ending the whole call
    or giving another task's row."""
    from scenarios.batch import engine

    def run_task(task):
        return _raising(task) if task.key == "b" else {"scene": task.scene.name, "e_ef_mm": 0.5, "key": task.key}

    monkeypatch.setattr(engine, "run_task", run_task)
    results = run_tasks([Task(k, _short()) for k in ("a", "b", "c")], client=client)
    assert results["a"] == {"scene": "bench_circle_PDq", "e_ef_mm": 0.5, "key": "a"} and results["c"]["key"] == "c"
    failed = results["b"]
    assert {k: failed[k] for k in ("scene", "outcome", "completed", "settled")} == {
        "scene": "bench_circle_PDq", "outcome": "failed", "completed": False, "settled": False}
    assert failed["error"]["message"] == "MemoryError: worker of b ran out of memory"
    assert failed["error"]["kind"] == "failed"
    for name in ("e_ef_mm", "tau_ef_Nm", "e_ss_mm", "e_ss_1s_mm", "t_settle_s", "wall_s"):
        assert failed[name] != failed[name], name      # NaN


def test_without_a_client_it_opens_one_with_the_options_and_builds_fmus_once(client, monkeypatch):
    """No client: one is opened with the scheduler, workers and processes given, and used; tasks
    in ``fmu`` mode have their FMUs built once beforehand, every model named once, sorted
    (an FMU file given by path is not built).  Catches the options not reaching the cluster,
    a second cluster, models built per task or not at all."""
    import contextlib

    from fmus.export import build
    from scenarios.batch import engine

    opened, built = [], []

    @contextlib.contextmanager
    def open_client_(scheduler=None, workers=None, processes=True):
        opened.append((scheduler, workers, processes))
        yield client

    monkeypatch.setattr(engine, "open_client", open_client_)
    monkeypatch.setattr(build, "ensure_built", built.append)
    monkeypatch.setattr(engine, "run_task", lambda task: {"key": task.key})
    scene = _short()
    by_file = replace(scene, system=replace(scene.system, components=tuple(
        replace(c, model="/nowhere/Derivator.fmu") if c.name == "deriv" else c for c in scene.system.components)))
    tasks = [Task("a", scene, mode="fmu"), Task("b", by_file, mode="fmu"), Task("c", scene)]
    results = run_tasks(tasks, scheduler="tcp://example:8786", workers=3, processes=False)
    assert results == {k: {"key": k} for k in "abc"}
    assert opened == [("tcp://example:8786", 3, False)]
    models = sorted({c.model for c in scene.system.components})
    assert built == [models]
    run_tasks([Task("d", scene)], client=client)
    assert len(built) == 1


def _slow(task):
    import time

    if task.key != "a":
        time.sleep(1.0)
    return {"key": task.key}


def test_an_interrupted_call_cancels_the_tasks_still_pending(client, monkeypatch):
    """``on_result`` raising at the first result (as a Ctrl-C in the caller does): the exception
    reaches the caller and the two tasks not done are cancelled on the cluster, the finished one
    not (the first to finish is "a", which does not sleep, on the one-thread worker).
    Catches the cancel skipped or given every future."""
    from scenarios.batch import engine

    cancelled = []
    cancel = client.cancel
    monkeypatch.setattr(client, "cancel", lambda futures: cancelled.append(sorted(f.key.split("-")[0]
                                                                                  for f in futures)) or cancel(futures))
    monkeypatch.setattr(engine, "run_task", _slow)

    first = []

    def stop(task, metrics):
        first.append(task.key)
        raise RuntimeError(f"stopped after {task.key}")

    with pytest.raises(RuntimeError, match="^stopped after [abc]$"):
        run_tasks([Task(k, _short()) for k in ("a", "b", "c")], client=client, on_result=stop)
    assert len(first) == 1 and cancelled == [sorted({"a", "b", "c"} - set(first))]
