"""What the sweep engine costs: per-task overhead against a plain loop, and 1 vs 2 workers.

``PYTHONPATH=. python benchmarks/bench_sweep.py [--scene bench_triangle_TCx] [--short 0.5] [--tasks 40]
[--samples 24]``

* Overhead: ``--tasks`` runs of the scene cut to ``--short`` s, once in a plain loop of
  :func:`scenarios.batch.engine.run_task` in this process, once through :func:`scenarios.batch.engine.run_tasks`
  on a LocalCluster of one worker process (warmed up first: kernels compiled, tables loaded);
  overhead per task = (engine wall - loop wall) / tasks.
* Scaling: a sweep of ``--samples`` full-length samples (U = 0.2) on warmed LocalClusters of 1
  and 2 worker processes; ratio = wall(1) / wall(2).

Wall times on a shared machine include whatever else runs: the script prints the load average
before and after.
"""
from __future__ import annotations

import argparse
import os
import time

from scenarios.batch.engine import Task, open_client, run_task, run_tasks
from scenarios.scenes.catalogue import get_scene
from scenarios.batch.sweep import run_sweep, with_stop_time


def _timed(call):
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def overhead(scene_name: str, short: float, n: int) -> dict:
    scene = with_stop_time(get_scene(scene_name), short)
    tasks = [Task(f"t{i}", scene) for i in range(n)]
    run_task(tasks[0])                                           # warm up this process
    loop = _timed(lambda: [run_task(t) for t in tasks])
    with open_client(workers=1) as client:
        run_tasks([Task("warm", scene)], client=client)         # warm up the worker
        engine = _timed(lambda: run_tasks(tasks, client=client))
    return {"tasks": n, "loop_s": loop, "engine_s": engine, "per_run_loop_ms": 1e3 * loop / n,
            "per_run_engine_ms": 1e3 * engine / n, "overhead_per_task_ms": 1e3 * (engine - loop) / n}


def scaling(scene_name: str, samples: int) -> dict:
    walls = {}
    for workers in (1, 2):
        with open_client(workers=workers) as client:
            run_sweep(scene_name, workers, 0.2, seed=1, client=client, plots=False)   # warm every worker
            walls[workers] = _timed(lambda: run_sweep(scene_name, samples, 0.2, client=client, plots=False))
    return {"samples": samples, "wall_1_s": walls[1], "wall_2_s": walls[2], "ratio": walls[1] / walls[2]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="bench_triangle_TCx")
    parser.add_argument("--short", type=float, default=0.5, help="simulated seconds of the overhead runs")
    parser.add_argument("--tasks", type=int, default=40)
    parser.add_argument("--samples", type=int, default=24)
    args = parser.parse_args(argv)
    print(f"load average before: {os.getloadavg()}")
    o = overhead(args.scene, args.short, args.tasks)
    print(f"overhead, {o['tasks']} runs of {args.scene} cut to {args.short:g} s: plain loop "
          f"{o['per_run_loop_ms']:.1f} ms/run, engine (1 worker) {o['per_run_engine_ms']:.1f} ms/run, "
          f"overhead {o['overhead_per_task_ms']:.1f} ms/task")
    s = scaling(args.scene, args.samples)
    print(f"scaling, {s['samples']} full samples of {args.scene}: 1 worker {s['wall_1_s']:.1f} s, "
          f"2 workers {s['wall_2_s']:.1f} s, ratio {s['ratio']:.2f}")
    print(f"load average after: {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
