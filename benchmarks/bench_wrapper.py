"""parcosim's FMI wrapper against pythonfmu 0.7's, on the same FMUs (issue 13).

Three measures, each side by side for the two binaries of one FMU (the FMU built by
``parcosim build``, and a copy whose ``binaries/linux64/<id>.so`` is pythonfmu's):

* **memory**: RSS growth per instantiate/setup/initialise/step/free cycle after a
  warm-up, and the growth of ``sys.path``;
* **speed**: µs per fmi2SetReal + fmi2DoStep + fmi2GetReal (one variable each), called
  through raw ctypes (fmpy's loaded library, no status checks in Python), both binaries
  in one process;
* **exit**: abnormal exits of a process that instantiates, initialises, steps once,
  frees and exits (pythonfmu: SIGABRT "corrupted double-linked list" in most runs).

Each measure runs in fresh processes, so a crash of pythonfmu's binary is counted, not
fatal::

    python -m benchmarks.bench_wrapper                  # all three, DCMotorDrive and FiveBarPlant exits
    python -m benchmarks.bench_wrapper --runs 20 --cycles 500 --calls 20000
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

DRIVER = r'''
import ctypes, json, os, sys, time
from ctypes import byref, c_double, c_size_t, c_uint, c_void_p
sys.path.insert(0, {support!r})
from fmi2raw import RawFmu

def rss_kb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1024

def cycle(fmu, steps=1):
    assert fmu.instantiate(), fmu.text()
    assert fmu.start() == [0, 0, 0], fmu.text()
    for k in range(steps):
        assert fmu.step(k * 1e-3, 1e-3) == 0, fmu.text()
    fmu.free()

def memory(path, warmup, cycles):
    fmu = RawFmu(path)
    for _ in range(warmup):
        cycle(fmu)
    path_before, rss_before = len(sys.path), rss_kb()
    for _ in range(cycles):
        cycle(fmu)
    return {{"kb_per_cycle": (rss_kb() - rss_before) / cycles, "sys_path_growth": len(sys.path) - path_before}}

def speed(paths, calls, repeats, input_name, output_name):
    fmus = [RawFmu(p) for p in paths]
    for fmu in fmus:
        assert fmu.instantiate(), fmu.text()
        assert fmu.start() == [0, 0, 0], fmu.text()
    result = []
    for fmu in fmus:
        lib, c = fmu.lib, fmu.c
        set_real, do_step, get_real = lib.fmi2SetReal, lib.fmi2DoStep, lib.fmi2GetReal
        vin, vout = (c_uint * 1)(fmu.vars[input_name][0]), (c_uint * 1)(fmu.vars[output_name][0])
        value, out, one = (c_double * 1)(0.1), (c_double * 1)(), c_size_t(1)
        fmu.t = 0.0
        result.append([set_real, do_step, get_real, c, vin, vout, value, out, one, fmu])
    best = [float("inf")] * len(fmus)
    for _ in range(repeats):
        for i, (set_real, do_step, get_real, c, vin, vout, value, out, one, fmu) in enumerate(result):
            t = fmu.t
            start = time.perf_counter()
            for _ in range(calls):
                set_real(c, vin, one, value)
                do_step(c, t, 1e-3, 1)
                get_real(c, vout, one, out)
                t += 1e-3
            best[i] = min(best[i], (time.perf_counter() - start) / calls * 1e6)
            fmu.t = t
    for fmu in fmus:
        fmu.free()
    return {{"us_per_call": best}}

def exit_run(path):
    fmu = RawFmu(path)
    cycle(fmu)
    return {{"ok": True}}

what = sys.argv[1]
args = json.loads(sys.argv[2])
print("RESULT " + json.dumps(globals()[what](**args)), flush=True)
'''


def with_binary(fmu: Path, binary: bytes, dest: Path) -> Path:
    """A copy of ``fmu`` at ``dest`` (unzipped) whose Linux binary is ``binary``."""
    from fmus.export.wrapper import model_identifier

    name = f"binaries/linux64/{model_identifier(fmu)}.so"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(dest)
    (dest / name).write_bytes(binary)
    return dest


def pythonfmu_binary() -> bytes:
    import pythonfmu

    return (Path(pythonfmu.__file__).parent / "resources" / "binaries" / "linux64" / "libpythonfmu-export.so").read_bytes()


def run(what: str, timeout: float = 600, **args):
    """Run DRIVER's function ``what`` in a fresh process: (result or None, exit status)."""
    source = DRIVER.format(support=str(ROOT / "tests" / "support"))
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", source, what, json.dumps(args)], capture_output=True, text=True,
                          env=env, timeout=timeout)
    lines = [line for line in proc.stdout.splitlines() if line.startswith("RESULT ")]
    return (json.loads(lines[-1][7:]) if lines else None), proc.returncode


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=20, help="processes per FMU and binary for the exit count")
    parser.add_argument("--cycles", type=int, default=1000, help="instantiate/free cycles measured (after --warmup)")
    parser.add_argument("--warmup", type=int, default=200)
    parser.add_argument("--measures", default="memory,speed,exit", help="which measures, comma-separated")
    parser.add_argument("--calls", type=int, default=20000, help="SetReal+DoStep+GetReal triples per repeat")
    parser.add_argument("--exit-models", default="DCMotorDrive,FiveBarPlant")
    parser.add_argument("--memory-models", default="Trajectory,DCMotorDrive,PositionController")
    args = parser.parse_args(argv)

    from fmus.export.build import build_fmu
    from fmus.export.wrapper import compiled_wrapper

    wrapper = compiled_wrapper()
    if wrapper is None:
        sys.exit("no C compiler: parcosim's wrapper cannot be built here")
    binaries = {"parcosim": wrapper.read_bytes(), "pythonfmu": pythonfmu_binary()}
    models = set(args.exit_models.split(",")) | set(args.memory_models.split(",")) | {"DCMotorDrive"}
    with tempfile.TemporaryDirectory(prefix="bench_wrapper_") as tmp:
        tmp = Path(tmp)
        paths = {}
        for model in sorted(models):
            fmu = build_fmu(model, tmp / "fmus")
            for label, binary in binaries.items():
                paths[model, label] = str(with_binary(fmu, binary, tmp / label / model))

        measures = args.measures.split(",")
        if "memory" in measures:
            memory(args, paths, binaries)
        if "speed" in measures:
            speed(args, paths, binaries)
        if "exit" in measures:
            exits(args, paths, binaries)


def memory(args, paths, binaries):
    """RSS and sys.path growth per cycle, each FMU and binary in its own process."""
    print(f"memory: RSS growth per instantiate/initialise/step/free cycle after {args.warmup} cycles, "
          f"over {args.cycles} cycles")
    print(f"{'FMU':<22}{'wrapper':<11}{'kB/cycle':>10}{'sys.path +':>12}")
    for model in args.memory_models.split(","):
        for label in binaries:
            result, status = run("memory", path=paths[model, label], warmup=args.warmup, cycles=args.cycles)
            if result is None:
                print(f"{model:<22}{label:<11}{'crashed (exit status ' + str(status) + ')':>22}")
            else:
                print(f"{model:<22}{label:<11}{result['kb_per_cycle']:>10.2f}{result['sys_path_growth']:>12d}")


def speed(args, paths, binaries):
    """µs per SetReal + DoStep + GetReal, both binaries in one process."""
    print(f"\nspeed: µs per fmi2SetReal(i_ref) + fmi2DoStep(1 ms) + fmi2GetReal(tau), DCMotorDrive, raw ctypes, "
          f"best of 5 x {args.calls}")
    result, status = run("speed", paths=[paths["DCMotorDrive", label] for label in binaries], calls=args.calls,
                         repeats=5, input_name="i_ref", output_name="tau")
    if result is None:
        print(f"crashed (exit status {status})")
    else:
        ours, theirs = result["us_per_call"]
        print(f"parcosim {ours:.2f} µs, pythonfmu {theirs:.2f} µs: parcosim/pythonfmu = {ours / theirs:.3f} "
              f"({theirs - ours:+.2f} µs per step saved)")


def exits(args, paths, binaries):
    """Abnormal exits over --runs processes per FMU and binary."""
    print(f"\nexit: abnormal exits of {args.runs} processes that instantiate, initialise, step once, free and exit")
    for model in args.exit_models.split(","):
        for label in binaries:
            statuses = [run("exit_run", path=paths[model, label])[1] for _ in range(args.runs)]
            bad = [s for s in statuses if s != 0]
            print(f"{model:<22}{label:<11}{len(bad):>3} of {args.runs} abnormal"
                  + (f" (exit statuses {sorted(set(bad))})" if bad else ""))


if __name__ == "__main__":
    main()
