"""Speed side by side in one run: the scene in its three modes beside the pass-through floors,
each component's cost per step on every path (Python in process, through its FMU, its compiled
kernel), a drive written in C through the master's FMU calls, and MuJoCo's step of the same 5R.

    python benchmarks/bench_components.py                          # bench_circle_TCMDx, 9 s, 3 rounds
    python benchmarks/bench_components.py --stop-time 2 --rounds 5

1. **The scene** (:func:`bench_master.measure`): in process, through the FMUs, the compiled
   loop and the two pass-through floors, ``--rounds`` interleaved rounds, median µs per step in
   wall and CPU time, the best round, the real-time factor and the 1-minute load average as each
   case finished; then the ratios between the cases.
2. **Per component** (the same rounds, timers on: ``bench_master.breakdown``), µs per
   communication step: the slave's own Python ``do_step`` in process; the master's whole call in
   process (inputs, ``do_step``, outputs) and through the FMU (``fmi2SetReal``, ``fmi2DoStep``,
   ``fmi2GetReal``); the instance's C I/O step (its adapter's ``kernel``,
   :mod:`fmus.cosim.compiled`) timed alone in the C loop, 500 calls from the state reached at
   the end of the run, its last inputs held, best of ``--rounds`` (a timer adds about 0.3 µs a
   call to the first three).
3. **One step of** a drive through :class:`fmus.cosim.backends._FmuInstance` (the master's FMU path):
   ``DCMotorDrive``'s FMU and the C drive of the foreign-FMU tests
   (``tests/support/cfmu/dcdrive.c``, built here when a C compiler is present), best of
   ``--rounds`` x 2000 steps; our drive's and plant's kernels (from 2.); MuJoCo's ``mj_step``
   (RK4, 1 ms) of the bench 5R from Python (``benchmarks/mujoco_5r.py``), when installed.

On a shared machine compare within one run, as ratios; the load average goes with each figure.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_master  # noqa: E402
from fmus.cosim import compiled  # noqa: E402
from fmus.cosim.master import simulate  # noqa: E402
from scenarios.scenes.catalogue import get_scene  # noqa: E402

CALLS = 2000
#: Calls of a kernel timed per round, from the state at the end of the run with its last inputs
#: held (the plant would reach a singular pose in a few thousand steps of held torques).
KERNEL_CALLS = 500


def compiled_plans(system):
    """Run ``system`` compiled and return its :class:`fmus.cosim.compiled.Plan` (state at the end)."""
    plans = []
    original = compiled.Plan.__init__

    def init(plan, *args, **kwargs):
        original(plan, *args, **kwargs)
        plans.append(plan)

    compiled.Plan.__init__ = init
    try:
        result = simulate(system, mode="compiled")
    finally:
        compiled.Plan.__init__ = original
    if result.error or not plans:
        raise RuntimeError(f"compiled run: {result.error or result.extra.get('fallback')}")
    return plans[0]


def kernel_us(plan, n: int, rounds: int) -> float:
    """µs per call of the ``n``-th member's C I/O step, alone in the C loop
    (:class:`fmus.cosim.compiled.LoopPlan` of that one member, no connections) for
    :data:`KERNEL_CALLS` steps from the state reached at the end of the run, its last inputs
    held; best of ``rounds`` (or of the calls before a refusal, if at least 50)."""
    adapter, member = plan.adapters[n], plan.loop.members[n]
    alone = compiled.LoopPlan([(1, [compiled.Member(member.io, member.context, adapter.x)])], [])
    values, record = np.zeros(1), np.zeros((KERNEL_CALLS + 1, 1))
    best = float("inf")
    for _ in range(rounds):
        start = time.perf_counter()
        stop = alone.run(values, record, 0, KERNEL_CALLS, 0.5, adapter.h)
        elapsed = time.perf_counter() - start
        if stop.step >= 50:
            best = min(best, elapsed / stop.step)
    return 1e6 * best


def fmu_drive_us(path, rounds: int) -> float:
    """µs per step of a drive FMU (inputs i_ref, v_ref, omega, i_hat; outputs tau, v, i)
    through the master's FMU instance, best of ``rounds`` × :data:`CALLS` steps of 0.25 ms."""
    from fmus.cosim.backends import _FmuInstance

    inst = _FmuInstance(Path(path), "drive")
    try:
        inst.initialize({}, 0.0)
        names_in = [n for n in ("i_ref", "v_ref", "omega", "i_hat") if n in inst.variables]
        inst.bind([inst.variables[n] for n in names_in], [inst.variables[n] for n in ("tau", "v", "i")])
        best, t = float("inf"), 0.0
        for _ in range(rounds):
            start = time.perf_counter()
            for k in range(CALLS):
                inst.set_inputs([0.1, 0.0, 1.0, 0.05][:len(names_in)])
                inst.do_step(t, 1e-3)
                inst.get_outputs()
                t += 1e-3
            best = min(best, (time.perf_counter() - start) / CALLS)
        return 1e6 * best
    finally:
        inst.close()


def _load() -> float:
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


def scene_table(runs) -> list:
    """Markdown rows of the scene in every mode, and the ratios between them."""
    from statistics import median

    med = {k: {q: median(r[q] for r in rs) for q in ("us_per_step", "cpu_us_per_step", "rtf", "load")}
           for k, rs in runs.items()}
    best = {k: min(r["us_per_step"] for r in rs) for k, rs in runs.items()}
    labels = {key: label for key, label, _, _ in bench_master.CASES}
    out = ["| case | µs/step (median) | best round | CPU µs/step | real-time factor | load (1 min) |",
           "|---|---:|---:|---:|---:|---:|"]
    for key, m in med.items():
        out.append(f"| {labels[key]} | {m['us_per_step']:.1f} | {best[key]:.1f} | {m['cpu_us_per_step']:.1f} | "
                   f"{m['rtf']:.1f}x | {m['load']:.1f} |")
    out += ["", "| ratio (same run) | wall, medians | wall, best rounds | CPU, medians |", "|---|---:|---:|---:|"]
    for label, a, b in (("through FMUs / FMU floor", "fmu", "floor_fmu"),
                        ("in process / in-process floor", "inprocess", "floor_inprocess"),
                        ("through FMUs / in process", "fmu", "inprocess"),
                        ("in process / compiled loop", "inprocess", "compiled"),
                        ("FMU floor / in-process floor", "floor_fmu", "floor_inprocess")):
        if a in med and b in med:
            out.append(f"| {label} | {med[a]['us_per_step'] / med[b]['us_per_step']:.2f} | "
                       f"{best[a] / best[b]:.2f} | {med[a]['cpu_us_per_step'] / med[b]['cpu_us_per_step']:.2f} |")
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="bench_circle_TCMDx")
    parser.add_argument("--stop-time", type=float, default=None, help="seconds of the scene (default: all of it)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--fmu-dir", default=None, help="our built FMUs (default fmus/build, built when stale)")
    args = parser.parse_args(argv)
    if args.rounds < 1:
        parser.error("--rounds must be >= 1")
    scene = get_scene(args.scene)
    system = scene.system if args.stop_time is None else replace(scene.system, stop_time=args.stop_time)
    print(f"{args.scene}, {system.stop_time:g} s ({system.steps} steps); {args.rounds} rounds; "
          f"load average before {'/'.join(f'{v:.2f}' for v in os.getloadavg())}")

    runs, timed, _, info, _ = bench_master.measure(system, args.rounds, args.fmu_dir)
    print(f"commit {info['commit']}" + (" + local edits" if info["modified_tracked_files"] else ""))
    print("\n**The scene**\n")
    print("\n".join(scene_table(runs)))

    breakdowns = {k: bench_master._median_breakdown(v) for k, v in timed.items() if v}
    plan = compiled_plans(system)
    kernels = {a.name: kernel_us(plan, n, args.rounds) for n, a in enumerate(plan.adapters)}
    kernel_load = _load()
    models = {c.name: c.model for c in system.components}
    python, fmu = breakdowns["inprocess"]["components"], breakdowns["fmu"]["components"]
    print(f"\n**Per component**, µs per step (timed rounds: load {_median_load(timed)}; kernels: load "
          f"{kernel_load:.1f})\n")
    print("| instance | model | Python do_step | master call in process | master call through FMU "
          "| compiled kernel | in process / kernel |")
    print("|---|---|---:|---:|---:|---:|---:|")
    sums = [0.0] * 4
    for name in plan.stepper.order:
        row = (python[name]["python_do_step"], sum(python[name][m] for m in bench_master.METHODS),
               sum(fmu[name][m] for m in bench_master.METHODS), kernels[name])
        sums = [a + b for a, b in zip(sums, row)]
        print(f"| {name} | {models[name]} | {row[0]:.1f} | {row[1]:.1f} | {row[2]:.1f} | {row[3]:.3f} | "
              f"{row[1] / row[3]:.0f} |")
    print(f"| **sum** | | {sums[0]:.1f} | {sums[1]:.1f} | {sums[2]:.1f} | {sums[3]:.3f} | {sums[1] / sums[3]:.0f} |")
    print(f"| master loop (rest of the step) | | | {breakdowns['inprocess']['rest_us']:.1f} | "
          f"{breakdowns['fmu']['rest_us']:.1f} | | |")

    rows = []
    from fmus.export.build import ensure_built

    ours = ensure_built(["DCMotorDrive"], args.fmu_dir)["DCMotorDrive"]
    rows.append(("DCMotorDrive FMU (ours: parcosim's wrapper, Python slave)", fmu_drive_us(ours, args.rounds), _load()))
    sys.path.insert(0, str(ROOT / "tests" / "support" / "cfmu"))
    from build import build_c_fmu, compiler

    if compiler() is not None:
        with tempfile.TemporaryDirectory() as tmp:
            rows.append(("DCDrive FMU (C, tests/support/cfmu)", fmu_drive_us(build_c_fmu("DCDrive", tmp), args.rounds),
                         _load()))
    drive_kernel = next((kernels[a.name] for a in plan.adapters if a.model == "DCMotorDrive"), float("nan"))
    rows.append(("DCMotorDrive compiled kernel (above)", drive_kernel, kernel_load))
    try:
        import mujoco_5r

        params = mujoco_5r.ref.params_bench()
        rows.append(("MuJoCo mj_step of the bench 5R (RK4, 1 ms, from Python)",
                     mujoco_5r.mujoco_step_time_us(params), _load()))
    except ImportError as exc:
        rows.append((f"MuJoCo: not installed ({exc})", float("nan"), _load()))
    plant = next((kernels[a.name] for a in plan.adapters if a.model in ("FiveBarPlant", "ActuatedFiveBarPlant")),
                 float("nan"))
    rows.append(("our plant, compiled kernel (above)", plant, kernel_load))
    print("\n**One step of**\n\n| one step of | µs | load (1 min) |\n|---|---:|---:|")
    for label, us, load in rows:
        print(f"| {label} | {us:.2f} | {load:.1f} |")
    print(f"\nload average after {'/'.join(f'{v:.2f}' for v in os.getloadavg())}")
    return 0


def _median_load(timed) -> str:
    from statistics import median

    loads = [r.get("load", float("nan")) for rs in timed.values() for r in rs]
    return f"{median(loads):.1f}" if loads else "n/a"


if __name__ == "__main__":
    raise SystemExit(main())
