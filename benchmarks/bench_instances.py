"""Memory per FMU instance: RSS growth per instantiate/free cycle, and ``sys.path`` (issue 13).

    python -m benchmarks.bench_instances [--cycles 300] [--warmup 300] [--fmu-dir DIR] [--models A,B]

For each FMU, in a fresh process each (so one FMU's growth is not another's):

* **through fmpy**: ``--warmup`` cycles, then twice ``--cycles`` cycles (RSS, then Python's
  allocations traced) of fmi2Instantiate,
  fmi2SetupExperiment, initialisation, one fmi2DoStep, fmi2Terminate, fmi2FreeInstance on
  the FMU's binary (pythonfmu 0.7's, or parcosim's FMI wrapper when the FMU has it); the
  process's RSS (``/proc/self/statm``) before and after, divided by the cycles;
* **the Python slave alone** (what is ours): the same cycle on the slave class called as
  the binary calls it, and the bytes still allocated by Python after it (``tracemalloc``),
  divided by the cycles;
* ``len(sys.path)`` before and after the fmpy cycles (pythonfmu's binary inserts the FMU's
  resources at every instantiation; :class:`fmus.slave.base.GuardedSlave` drops the duplicates).

Goal: at most 1 kB per cycle after warm-up, ``sys.path`` unchanged.
"""
from __future__ import annotations

import argparse
import gc
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def rss_bytes() -> int:
    """Resident set size of this process."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _fmpy_cycles(unzip_dir: str, warmup: int, cycles: int) -> dict:
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(unzip_dir)

    def cycle():
        # A new FMU2Slave each time, as fmpy.simulate_fmu does: fmpy's freeInstance also
        # unloads the library, after which the old object must not be used again.
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip_dir, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName="bench")
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        try:
            fmu.doStep(0.0, 1e-3)
        except Exception:   # noqa: BLE001 - a refused step (default inputs) is still a full cycle
            pass
        fmu.terminate()
        fmu.freeInstance()

    path_before = len(sys.path)
    rss, python, top = _measure(cycle, warmup, cycles)
    return {"rss_per_cycle_B": rss, "fmpy_python_per_cycle_B": python, "top": top,
            "sys_path_before": path_before, "sys_path_after": len(sys.path)}


def _measure(cycle, warmup: int, cycles: int):
    """(RSS growth per cycle, Python bytes kept per cycle, the three largest kept) after
    ``warmup`` cycles: RSS over ``cycles`` cycles first, untraced (tracemalloc's own
    records would count), then Python's allocations over as many, traced."""
    import tracemalloc

    for _ in range(warmup):
        cycle()
    gc.collect()
    before = rss_bytes()
    for _ in range(cycles):
        cycle()
    gc.collect()
    rss = (rss_bytes() - before) / cycles
    tracemalloc.start()
    start, _ = tracemalloc.get_traced_memory()
    for _ in range(cycles):
        cycle()
    gc.collect()
    end, _ = tracemalloc.get_traced_memory()
    snapshot = tracemalloc.take_snapshot()
    tracemalloc.stop()
    top = [f"{s.traceback[0].filename.rsplit('/', 2)[-1]}:{s.traceback[0].lineno} {s.size / cycles:.0f} B"
           for s in snapshot.statistics("lineno")[:3]]
    return rss, (end - start) / cycles, top


def _slave_cycles(model: str, warmup: int, cycles: int) -> dict:
    import importlib

    from fmus.slave.registry import SLAVES

    cls = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)

    def cycle():
        slave = cls(instance_name="bench")
        slave.setup_experiment(0.0, None, None)
        slave.enter_initialization_mode()
        slave.exit_initialization_mode()
        slave.do_step(0.0, 1e-3)
        slave.terminate()
        del slave

    rss, python, _ = _measure(cycle, warmup, cycles)
    return {"python_per_cycle_B": python, "slave_rss_per_cycle_B": rss}


def _child(args) -> None:
    """One FMU in this process: print its figures as JSON."""
    if args.mode == "fmpy":
        figures = _fmpy_cycles(args.unzip, args.warmup, args.cycles)
    else:
        figures = _slave_cycles(args.model, args.warmup, args.cycles)
    print(json.dumps(figures))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_instances", description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=300, help="measured cycles (default 300)")
    parser.add_argument("--warmup", type=int, default=300, help="unmeasured cycles first (default 300: RSS settles after about 300 controller instances)")
    parser.add_argument("--fmu-dir", default=None, help="the built FMUs (default: built into a temporary directory)")
    parser.add_argument("--models", default=None, help="comma-separated FMUs (default: all)")
    parser.add_argument("--verbose", action="store_true", help="name the largest allocations kept")
    parser.add_argument("--child", choices=("fmpy", "slave"), dest="mode", help=argparse.SUPPRESS)
    parser.add_argument("--unzip", help=argparse.SUPPRESS)
    parser.add_argument("--model", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.mode:
        _child(args)
        return 0

    from fmus.hostile.cases import prepared_fmus

    work = Path(tempfile.mkdtemp(prefix="parcosim-bench-instances-"))
    unzipped = prepared_fmus(args.fmu_dir, args.models, work)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    print(f"{args.warmup} warm-up cycles, then {args.cycles} measured; a fresh process per FMU and mode")
    print(f"| FMU | RSS per cycle through fmpy [B] | Python bytes kept per cycle through fmpy [B] | "
          f"Python bytes kept per cycle, slave alone [B] | RSS per cycle, slave alone [B] | "
          f"sys.path before -> after {args.cycles + args.warmup} instances |")
    print("|---|---|---|---|---|---|")
    for model, unzip in unzipped.items():
        common = [sys.executable, "-m", "benchmarks.bench_instances", "--warmup", str(args.warmup),
                  "--cycles", str(args.cycles)]
        fmpy = subprocess.run(common + ["--child", "fmpy", "--unzip", str(unzip)], env=env, capture_output=True,
                              text=True, cwd=ROOT)
        slave = subprocess.run(common + ["--child", "slave", "--model", model], env=env, capture_output=True,
                               text=True, cwd=ROOT)
        try:
            f = json.loads(fmpy.stdout.strip().splitlines()[-1])
            s = json.loads(slave.stdout.strip().splitlines()[-1])
        except (IndexError, json.JSONDecodeError):
            print(f"| {model} | failed: {(fmpy.stderr or slave.stderr)[-300:]!r} | | | |")
            continue
        print(f"| {model} | {f['rss_per_cycle_B']:.0f} | {f['fmpy_python_per_cycle_B']:.0f} | "
              f"{s['python_per_cycle_B']:.0f} | {s['slave_rss_per_cycle_B']:.0f} | "
              f"{f['sys_path_before']} -> {f['sys_path_after']} |", flush=True)
        if args.verbose:
            print(f"    largest Python allocations kept through fmpy: {f['top']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
