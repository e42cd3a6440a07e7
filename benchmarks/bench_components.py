"""Per-component cost of one step, side by side in one run: our Python path, the compiled kernel,
a drive written in C through the master's FMU calls, and MuJoCo's step of the same 5R.

    python benchmarks/bench_components.py                 # bench_circle_TCMDx, 2 s of it
    python benchmarks/bench_components.py --stop-time 9 --rounds 7

For each instance of the scene, µs per communication step:

* **Python (in process)**: the slave's own ``do_step`` inside an in-process run, and the whole
  master call (inputs, ``do_step``, outputs), timed by ``bench_master.breakdown`` (a timer adds
  about 0.3 µs a call);
* **compiled kernel**: the instance's line of the compiled loop (its adapter's ``emit``,
  :mod:`fmus.compiled`) in a compiled loop of 500 calls from the state reached at the end of the
  run, its last inputs held, the best of ``--rounds`` (nothing but the kernel: its share of the
  compiled loop);
* **through the FMU**: for the drives, ``DCMotorDrive``'s FMU and the C drive of the foreign-FMU
  tests (``tests/support/cfmu/dcdrive.c``, built here when a C compiler is present), each
  through :class:`fmus.instances._FmuInstance` (one ``fmi2SetReal``, ``fmi2DoStep``,
  ``fmi2GetReal`` a step, the master's own path), best of ``--rounds`` × 2000 steps;
* **MuJoCo**: one ``mj_step`` (RK4, 1 ms) of the bench 5R from Python
  (``benchmarks/mujoco_5r.py``), when mujoco is installed.

Figures on a shared machine: compare within one run, as ratios; the load average is printed.
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
from numba import njit  # noqa: F401 - used by the generated timing loops

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_master  # noqa: E402
from fmus import compiled  # noqa: E402
from fmus.master import simulate  # noqa: E402
from scenarios.scenes import get_scene  # noqa: E402

CALLS = 2000
#: Calls of a kernel timed per round, from the state at the end of the run with its last inputs
#: held (the plant would reach a singular pose in a few thousand steps of held torques).
KERNEL_CALLS = 500


def compiled_plans(system) -> list:
    """Run ``system`` compiled and return its :class:`fmus.compiled.Plan` (state at the end)."""
    plans = []
    original = compiled.Plan.load

    def load(plan):
        plans.append(plan)
        return original(plan)

    compiled.Plan.load = load
    try:
        result = simulate(system, mode="compiled")
    finally:
        compiled.Plan.load = original
    if result.error or not plans:
        raise RuntimeError(f"compiled run: {result.error or result.extra.get('fallback')}")
    return plans[0]


def kernel_us(adapter, rounds: int) -> float:
    """µs per call of ``adapter``'s compiled line, best of ``rounds`` loops of :data:`KERNEL_CALLS`
    (or of the calls before a refusal, if at least 50)."""
    arrays = [f"a{k}" for k in range(len(adapter.arrays))]
    body = "\n".join("        " + line for line in adapter.emit(arrays, "x", "0.5", repr(adapter.h)))
    source = (f"def loop({', '.join(arrays)}, x, n):\n    for k in range(n):\n{body}\n        if st != 0:\n"
              "            return k\n    return n\n")
    namespace = {}
    for m in adapter.modules:
        package, _, name = m.rpartition(".")
        namespace[name] = __import__(m, fromlist=[name])
    exec(compile(source, f"<timing loop of {adapter.name}>", "exec"), namespace)
    loop = njit(namespace["loop"])
    best = float("inf")
    for r in range(rounds + 1):
        args = [a.copy() for a in adapter.arrays] + [adapter.x.copy()]
        start = time.perf_counter()
        done = loop(*args, KERNEL_CALLS if r else 1)
        elapsed = time.perf_counter() - start
        if r and done >= 50:
            best = min(best, elapsed / done)
    return 1e6 * best


def fmu_drive_us(path, rounds: int) -> float:
    """µs per step of a drive FMU (inputs i_ref, v_ref, omega, i_hat; outputs tau, v, i)
    through the master's FMU instance, best of ``rounds`` × :data:`CALLS` steps of 0.25 ms."""
    from fmus.instances import _FmuInstance

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


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="bench_circle_TCMDx")
    parser.add_argument("--stop-time", type=float, default=2.0)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--fmu-dir", default=None, help="our built FMUs (default fmus/build, built when stale)")
    args = parser.parse_args(argv)
    scene = get_scene(args.scene)
    system = replace(scene.system, stop_time=args.stop_time)
    print(f"{args.scene}, {args.stop_time:g} s; load average before {'/'.join(f'{v:.2f}' for v in os.getloadavg())}")

    bench_master.breakdown(replace(system, stop_time=0.05), "inprocess", None)        # warm-up
    python = bench_master.breakdown(system, "inprocess", None)["components"]
    plan = compiled_plans(system)
    kernels = {a.name: kernel_us(a, args.rounds) for a in plan.adapters}
    models = {c.name: c.model for c in system.components}

    print("\n| instance | model | Python do_step [µs] | master call in process [µs] | compiled kernel [µs] "
          "| Python / compiled |")
    print("|---|---|---:|---:|---:|---:|")
    for name in plan.stepper.order:
        p = python[name]
        total = sum(p[m] for m in bench_master.METHODS)
        print(f"| {name} | {models[name]} | {p['python_do_step']:.1f} | {total:.1f} | {kernels[name]:.3f} | "
              f"{total / kernels[name]:.0f} |")
    total_python = sum(sum(p[m] for m in bench_master.METHODS) for p in python.values())
    print(f"| **sum** | | {sum(p['python_do_step'] for p in python.values()):.1f} | {total_python:.1f} | "
          f"{sum(kernels.values()):.3f} | {total_python / sum(kernels.values()):.0f} |")

    rows = []
    from fmus.build import ensure_built

    ours = ensure_built(["DCMotorDrive"], args.fmu_dir)["DCMotorDrive"]
    rows.append(("DCMotorDrive FMU (ours, pythonfmu)", fmu_drive_us(ours, args.rounds)))
    sys.path.insert(0, str(ROOT / "tests" / "support" / "cfmu"))
    from build import build_c_fmu, compiler

    if compiler() is not None:
        with tempfile.TemporaryDirectory() as tmp:
            rows.append(("DCDrive FMU (C, tests/support/cfmu)", fmu_drive_us(build_c_fmu("DCDrive", tmp), args.rounds)))
    drive_kernel = next((kernels[a.name] for a in plan.adapters if a.model == "DCMotorDrive"), float("nan"))
    rows.append(("DCMotorDrive compiled kernel (above)", drive_kernel))
    try:
        import mujoco_5r

        params = mujoco_5r.ref.params_bench()
        rows.append(("MuJoCo mj_step of the bench 5R (RK4, 1 ms, from Python)", mujoco_5r.mujoco_step_time_us(params)))
    except ImportError as exc:
        rows.append((f"MuJoCo: not installed ({exc})", float("nan")))
    plant = next((kernels[a.name] for a in plan.adapters if a.model in ("FiveBarPlant", "ActuatedFiveBarPlant")),
                 float("nan"))
    rows.append(("our plant, compiled kernel (above)", plant))
    print("\n| one step of | µs |\n|---|---:|")
    for label, us in rows:
        print(f"| {label} | {us:.2f} |")
    print(f"\nload average after {'/'.join(f'{v:.2f}' for v in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
