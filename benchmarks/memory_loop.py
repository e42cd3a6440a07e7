"""Memory over many runs in one process: does the resident set grow with the runs?

    python benchmarks/memory_loop.py                       # 1000 runs each of in-process and compiled
    python benchmarks/memory_loop.py --runs 200 --every 20 --stop-time 0.1

Runs ``--scene`` (default bench_circle_TCMDx, shortened to ``--stop-time`` s so that 1000 runs
take minutes: say so when quoting) ``--runs`` times with ``simulate(..., mode)`` for each mode,
one after the other in this process, and prints the resident set (VmRSS of /proc/self/status,
the present size, not the peak: ``ru_maxrss`` never goes down) after every ``--every`` runs,
and the growth from the first print to the last.  docs/benchmarks.md quotes a run.
"""
from __future__ import annotations

import argparse
import gc
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fmus.cosim.master import simulate  # noqa: E402
from scenarios.scenes.catalogue import get_scene  # noqa: E402


def rss_mb() -> float:
    """The process's present resident set size [MB] (Linux: VmRSS of /proc/self/status)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS in /proc/self/status")


def loop(system, mode: str, runs: int, every: int, report=print) -> list:
    """Run ``system`` ``runs`` times; the (run, RSS MB) pairs measured after every ``every`` runs
    (after a garbage collection, so that only memory still referenced counts)."""
    samples = []
    for k in range(1, runs + 1):
        result = simulate(system, mode=mode)
        if result.error:
            raise RuntimeError(f"run {k} ({mode}): {result.error}")
        del result
        if k % every == 0 or k == runs:
            gc.collect()
            samples.append((k, rss_mb()))
            report(f"{mode:10s} run {k:5d}: RSS {samples[-1][1]:8.1f} MB")
    return samples


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="bench_circle_TCMDx")
    parser.add_argument("--stop-time", type=float, default=0.2, help="shortened scene [s] (default 0.2)")
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--every", type=int, default=100)
    parser.add_argument("--modes", default="inprocess,compiled")
    args = parser.parse_args(argv)
    scene = get_scene(args.scene)
    system = replace(scene.system, stop_time=args.stop_time)
    print(f"{args.scene} shortened to {args.stop_time:g} s, {args.runs} runs per mode; RSS at start {rss_mb():.1f} MB")
    for mode in args.modes.split(","):
        start = time.perf_counter()
        samples = loop(system, mode, args.runs, args.every)
        first, last = samples[0][1], samples[-1][1]
        print(f"{mode}: RSS after run {samples[0][0]} {first:.1f} MB, after run {samples[-1][0]} {last:.1f} MB: "
              f"{last - first:+.1f} MB over {samples[-1][0] - samples[0][0]} runs "
              f"({time.perf_counter() - start:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
