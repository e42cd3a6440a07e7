"""The compiled loop with two (or more) builds of the C kernels, side by side in one run.

    python benchmarks/bench_compiled_libs.py --lib base=/tmp/base.so --lib new=kernels/libparcosim_kernels.so
    python benchmarks/bench_compiled_libs.py --lib base=A.so --lib new=B.so --rounds 7 --stop-time 9

Each round runs, for every library in turn (so load from elsewhere hits them alike), a fresh
process with ``$PARCOSIM_KERNELS_LIB`` set to it that

* runs ``--scene`` (default bench_circle_TCMDx) :data:`RUNS` times with
  ``simulate(system, mode="compiled")`` and times the stepping of the run of least CPU time
  (the C loop, ``Result.extra["cpu_s"]``: CPU time of the thread, and ``wall_s``), per
  communication step;
* times each instance's C I/O step alone in the C loop (``bench_components.kernel_us``: 500
  calls from the state reached at the end of the run, its last inputs held, best of 5), in ns;
* checks that the run's recorded rows are the same (bit for bit) for every library, and
  prints the final e_ef of the scene.

The Python side (the adapters, the plan) is this checkout's for every library, so the
libraries must share the structs' layouts.  Printed: the median over the rounds of each
figure, and the ratios to the first library.

``--digests`` instead runs every scene of ``parcosim list`` compiled once with each library
and prints the scenes whose recorded rows differ (SHA-256 of the result columns): a change
meant to leave every result alone (flags, reordered loops) must list none.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Runs of the scene per process; its figure is the run of least CPU time.
RUNS = 3


def child(scene: str, stop_time: float | None) -> dict:
    """One measurement in this process (the library is ``$PARCOSIM_KERNELS_LIB``)."""
    from dataclasses import replace

    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import bench_components
    from fmus.cosim.master import simulate
    from scenarios.run.metrics import scene_metrics
    from scenarios.run.runner import result_columns
    from scenarios.scenes.catalogue import get_scene

    the_scene = get_scene(scene)
    if stop_time is not None:
        the_scene = replace(the_scene, system=replace(the_scene.system, stop_time=stop_time))
    system = the_scene.system
    simulate(replace(system, stop_time=min(system.stop_time, 0.1)), mode="compiled")   # warm-up
    runs = [simulate(system, mode="compiled") for _ in range(RUNS)]
    result = min(runs, key=lambda r: r.extra["cpu_s"])
    if result.error or result.extra.get("fallback"):
        raise RuntimeError(f"compiled run: {result.error or result.extra.get('fallback')}")
    steps = system.steps
    plan = bench_components.compiled_plans(system)
    kernel_ns = {a.name: 1e3 * bench_components.kernel_us(plan, n, 5) for n, a in enumerate(plan.adapters)}
    columns = result_columns(the_scene, result)
    e_ef = scene_metrics(the_scene, columns, result.wall_s, result.completed)["e_ef_mm"]
    return {"cpu_ns_per_step": 1e9 * result.extra["cpu_s"] / steps, "wall_ns_per_step": 1e9 * result.wall_s / steps,
            "kernel_ns": kernel_ns, "rows_sha256": _digest(the_scene, result), "e_ef_mm": e_ef, "step": system.step}


def _digest(the_scene, result) -> str:
    import hashlib

    import numpy as np
    from scenarios.run.runner import result_columns

    columns = result_columns(the_scene, result)
    return hashlib.sha256(b"".join(np.ascontiguousarray(columns[k]).tobytes() for k in sorted(columns))).hexdigest()[:16]


def digest_child() -> dict:
    """Scene -> digest of its compiled run's rows (or the error), every scene, this process's library."""
    import warnings

    sys.path.insert(0, str(ROOT))
    from fmus.cosim.master import simulate
    from scenarios.scenes.catalogue import get_scene, scene_names

    warnings.simplefilter("ignore")   # fall-back warnings: the mode that ran is in the digest's line
    out = {}
    for name in scene_names():
        scene = get_scene(name)
        try:
            result = simulate(scene.system, mode="compiled")
            out[name] = f"{_digest(scene, result)} {result.mode}" + (f" error: {result.error}" if result.error else "")
        except Exception as exc:  # noqa: BLE001 - a scene that cannot run is a line of the comparison
            out[name] = f"{type(exc).__name__}: {exc}"
    return out


def _child_json(path: str, flag: str, *extra) -> dict:
    env = dict(os.environ, PARCOSIM_KERNELS_LIB=str(Path(path).resolve()))
    out = subprocess.run([sys.executable, __file__, flag, *extra], env=env, cwd=ROOT, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def compare_digests(libs: dict) -> int:
    """Print the scenes whose compiled rows differ between the libraries; 1 if any does."""
    digests = {label: _child_json(path, "--digest-child") for label, path in libs.items()}
    first, *others = digests
    differ = [name for name in digests[first] if any(digests[o].get(name) != digests[first][name] for o in others)]
    modes = sorted({line.split()[1] for line in digests[first].values() if len(line.split()) > 1})
    print(f"{len(digests[first])} scenes compiled ({', '.join(modes)}), {len(differ)} with different rows")
    for name in differ:
        print(f"  {name}: " + "; ".join(f"{label} {d[name]}" for label, d in digests.items()))
    return 1 if differ else 0


def measure_once(path: str, scene: str, stop_time) -> dict:
    extra = ["--scene", scene] + (["--stop-time", str(stop_time)] if stop_time is not None else [])
    return _child_json(path, "--child", *extra)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lib", action="append", default=[], metavar="LABEL=PATH",
                        help="a build of kernels/src (repeat; the first is the reference of the ratios)")
    parser.add_argument("--scene", default="bench_circle_TCMDx")
    parser.add_argument("--stop-time", type=float, default=None, help="seconds of the scene (default: all)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--digests", action="store_true", help="compare every scene's compiled rows instead")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--digest-child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        print(json.dumps(child(args.scene, args.stop_time)))
        return 0
    if args.digest_child:
        print(json.dumps(digest_child()))
        return 0
    if len(args.lib) < 1 or any("=" not in s for s in args.lib):
        parser.error("give --lib LABEL=PATH at least once")
    libs = dict(s.split("=", 1) for s in args.lib)
    if args.digests:
        return compare_digests(libs)
    runs = {label: [] for label in libs}
    for _ in range(args.rounds):
        for label, path in libs.items():
            runs[label].append(measure_once(path, args.scene, args.stop_time))
    load = "/".join(f"{v:.2f}" for v in os.getloadavg())
    med = {}
    for label, rs in runs.items():
        kernels = {name: statistics.median(r["kernel_ns"][name] for r in rs) for name in rs[0]["kernel_ns"]}
        cpu = statistics.median(r["cpu_ns_per_step"] for r in rs)
        med[label] = {"cpu": cpu, "best_cpu": min(r["cpu_ns_per_step"] for r in rs),
                      "wall": statistics.median(r["wall_ns_per_step"] for r in rs), "kernels": kernels,
                      "rtf_cpu": rs[0]["step"] / (1e-9 * cpu), "sha": {r["rows_sha256"] for r in rs},
                      "e_ef": {r["e_ef_mm"] for r in rs}}
    first = next(iter(med))
    print(f"{args.scene}, {args.rounds} rounds, load average at the end {load}")
    print("| figure | " + " | ".join(med) + " | " + " | ".join(f"{k} / {first}" for k in list(med)[1:]) + " |")
    print("|---|" + "---:|" * (2 * len(med) - 1))

    def row(name, get, fmt="{:.0f}"):
        values = [get(m) for m in med.values()]
        ratios = [f"{v / values[0]:.2f}" for v in values[1:]]
        print(f"| {name} | " + " | ".join(fmt.format(v) for v in values) + " | " + " | ".join(ratios) + " |")

    row("loop, CPU ns/step (median)", lambda m: m["cpu"])
    row("loop, CPU ns/step (best)", lambda m: m["best_cpu"])
    row("loop, wall ns/step (median)", lambda m: m["wall"])
    row("real-time factor (CPU, median)", lambda m: m["rtf_cpu"], "{:.0f}x")
    for name in med[first]["kernels"]:
        row(f"kernel {name}, ns/call", lambda m, n=name: m["kernels"][n])
    row("sum of kernels, ns", lambda m: sum(m["kernels"].values()))
    row("loop minus kernels, ns", lambda m: m["cpu"] - sum(m["kernels"].values()))
    for label, m in med.items():
        print(f"{label}: rows sha256 {sorted(m['sha'])}, e_ef {sorted(m['e_ef'], key=str)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
