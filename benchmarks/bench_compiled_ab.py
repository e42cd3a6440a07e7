"""Two builds of the C kernels in one process, their compiled loops interleaved chunk by chunk.

    python benchmarks/bench_compiled_ab.py --lib main=/tmp/main.so --lib this=kernels/libparcosim_kernels.so
    python benchmarks/bench_compiled_ab.py --lib main=A.so --lib this=B.so --repeats 8

For a loaded machine, where a process-per-build comparison (bench_compiled_libs.py) scatters
by 10-15 % between identical builds (the load, not the code, decides which process is slow).
The first library is the one this process loads (``$PARCOSIM_KERNELS_LIB``: the process
re-executes itself with it set) and builds the plan (the adapters, the contexts); the second
is loaded beside it with ctypes and lends only its ``pc_loop_run`` and each member's I/O
step, looked up by name.  Both libraries must share the structs' layouts and the Python side's
expectations (this checkout's).

* **The loop**: ``--scene`` (default bench_circle_TCMDx) run compiled ``--repeats`` times.  The
  run's chunks (the compiled mode steps in chunks of 1 % of the run) alternate between the two
  builds, the first chunk's build alternating between repeats; each chunk's CPU time of the
  thread per step is kept (the first chunk of a run, cold, is not).  Printed: the minimum, the
  10th percentile and the median of each build's chunks and their ratios.  The two builds
  advance the same state: if they differed in a single bit the run would differ from a run of
  either alone, so the first library's rows digest is printed and must be the build's own.
* **Each member alone** (as ``bench_components.kernel_us``): its I/O step in a one-member loop
  from the state at the end of a run, inputs held, 100 calls a burst, the two builds' bursts
  alternating, ``--bursts`` each: the minimum and the median ns a call.

Ratios < 1 mean the second library is faster.
"""
from __future__ import annotations

import argparse
import ctypes
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Calls of one member's I/O step per burst.
BURST = 100


def _address(lib, name: str) -> int:
    return ctypes.cast(getattr(lib, name), ctypes.c_void_p).value


def _call_loop(run, plan_struct, values, record, k0: int, k1: int, t: float, h: float):
    from fmus.cosim import compiled
    from kernels import address

    stop = compiled._LoopStop()
    run(ctypes.byref(plan_struct), ctypes.c_void_p(address(values)), ctypes.c_void_p(address(record)),
        ctypes.c_int64(k0), ctypes.c_int64(k1), ctypes.c_double(t), ctypes.c_double(h), ctypes.byref(stop))
    return stop


def loop_chunks(scene, libs: dict, repeats: int) -> tuple[dict, str]:
    """Label -> the CPU ns per step of each of its chunks; and the rows digest of the last run
    (``bench_compiled_libs``'s)."""
    import numpy as np

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from bench_compiled_libs import _digest
    from fmus.cosim import compiled
    from fmus.cosim.master import simulate

    labels = list(libs)
    chunks = {label: [] for label in labels}
    turn = {"repeat": 0, "chunk": 0}

    def run(plan, values, record, k0, k1, t, h):
        io = plan.loop._pointers["io"]
        if not hasattr(plan, "ab_io"):
            plan.ab_io = {label: np.array([_address(lib, a.kernel) for a in plan.adapters], dtype=np.uintp)
                          for label, lib in libs.items()}
        label = labels[(turn["chunk"] + turn["repeat"]) % 2]
        turn["chunk"] += 1
        io[:] = plan.ab_io[label]
        start = time.thread_time_ns()
        stop = _call_loop(libs[label].pc_loop_run, plan.loop.struct, values, record, k0, k1, t, h)
        elapsed = time.thread_time_ns() - start
        if k0 > 0 and stop.step > k0:
            chunks[label].append(elapsed / (stop.step - k0))
        return stop

    original = compiled.Plan.run
    compiled.Plan.run = run
    try:
        for r in range(repeats):
            turn.update(repeat=r, chunk=0)
            result = simulate(scene.system, mode="compiled")
            if result.error or not result.completed or result.extra.get("python_steps"):
                raise RuntimeError(f"compiled run: {result.error or 'not completed in C'}")
    finally:
        compiled.Plan.run = original
    return chunks, _digest(scene, result)


def members_alone(system, libs: dict, bursts: int) -> list:
    """(member, {label: (min, median) ns per call}) of each member's I/O step alone."""
    import statistics

    import numpy as np

    sys.path.insert(0, str(ROOT / "benchmarks"))
    import bench_components
    from fmus.cosim import compiled

    plan = bench_components.compiled_plans(system)
    rows = []
    for n, adapter in enumerate(plan.adapters):
        member = plan.loop.members[n]
        alone = {label: compiled.LoopPlan([(1, [compiled.Member(_address(lib, adapter.kernel), member.context,
                                                                 adapter.x)])], [])
                 for label, lib in libs.items()}
        values, record = np.zeros(1), np.zeros((BURST + 1, 1))
        times = {label: [] for label in libs}
        order = list(libs)
        for b in range(bursts):
            for label in (order if b % 2 == 0 else order[::-1]):
                start = time.perf_counter_ns()
                stop = _call_loop(libs[label].pc_loop_run, alone[label].struct, values, record, 0, BURST, 0.5,
                                  adapter.h)
                elapsed = time.perf_counter_ns() - start
                if stop.step >= BURST // 2:
                    times[label].append(elapsed / stop.step)
        rows.append((adapter.name, {label: (min(ts), statistics.median(ts)) for label, ts in times.items()}))
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lib", action="append", default=[], metavar="LABEL=PATH",
                        help="a build of kernels/src (twice: the first is the reference of the ratios)")
    parser.add_argument("--scene", default="bench_circle_TCMDx")
    parser.add_argument("--repeats", type=int, default=6, help="runs of the scene (default 6)")
    parser.add_argument("--bursts", type=int, default=300, help="bursts per build and member alone (default 300)")
    args = parser.parse_args(argv)
    if len(args.lib) != 2 or any("=" not in s for s in args.lib):
        parser.error("give --lib LABEL=PATH twice")
    libs = {label: str(Path(path).resolve()) for label, path in (s.split("=", 1) for s in args.lib)}
    first = next(iter(libs.values()))
    if os.environ.get("PARCOSIM_KERNELS_LIB") != first:
        env = dict(os.environ, PARCOSIM_KERNELS_LIB=first)
        os.execve(sys.executable, [sys.executable, __file__, *(argv if argv is not None else sys.argv[1:])], env)
    sys.path.insert(0, str(ROOT))
    import numpy as np

    import kernels
    from scenarios.scenes.catalogue import get_scene

    loaded = {label: kernels.library() if path == first else ctypes.CDLL(path) for label, path in libs.items()}
    scene = get_scene(args.scene)
    chunks, digest = loop_chunks(scene, loaded, args.repeats)
    (la, a), (lb, b) = ((label, np.array(v)) for label, v in chunks.items())
    print(f"{args.scene}, {args.repeats} runs, chunks {a.size} {la} / {b.size} {lb}, "
          f"load average {'/'.join(f'{v:.2f}' for v in os.getloadavg())}; rows digest {digest}")
    print(f"| loop, CPU ns per step | {la} | {lb} | {lb} / {la} |")
    print("|---|---:|---:|---:|")
    for name, f in (("min of the chunks", np.min), ("10th percentile", lambda x: np.percentile(x, 10)),
                    ("median", np.median)):
        print(f"| {name} | {f(a):.0f} | {f(b):.0f} | {f(b) / f(a):.3f} |")
    rows = members_alone(scene.system, loaded, args.bursts)
    print(f"\n| member alone, ns a call (min; median) | {la} | {lb} | {lb} / {la} (min; median) |")
    print("|---|---:|---:|---:|")
    for name, t in rows + [("sum", {label: tuple(sum(r[1][label][i] for r in rows) for i in (0, 1))
                                    for label in (la, lb)})]:
        print(f"| {name} | {t[la][0]:.0f}; {t[la][1]:.0f} | {t[lb][0]:.0f}; {t[lb][1]:.0f} | "
              f"{t[lb][0] / t[la][0]:.3f}; {t[lb][1] / t[la][1]:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
