"""Cold start of parcosim's FMUs against a small C FMU (issue 27, item 5).

A *cold* run is ``fmpy.simulate_fmu(fmu, stop_time=0.01, output_interval=1e-3)`` in a fresh
Python process that has not imported parcosim, whose caches are all new empty folders (HOME,
XDG_CACHE_HOME, XDG_CONFIG_HOME, XDG_DATA_HOME, PARCOSIM_CACHE, NUMBA_CACHE_DIR,
PARCOSIM_COMPILED_CACHE, TMPDIR), started in an empty working folder.  The process's CPU
(user + sys, ``os.wait4`` of that child alone) and wall time are measured from outside; the
baseline is the same run of a first-order low-pass FMU written in C
(``benchmarks/baseline_fmu``), so the difference is what our FMUs cost over what fmpy and
the interpreter cost anyway.  The goal: at most 1 s of CPU more than the baseline.

Measured: PositionController and FiveBarPlant (as ``parcosim build`` builds them,
:func:`fmus.export.build.build_fmu`), the ``ClosedLoop`` of ``bench_circle_TCMDx`` (as ``parcosim
export-fmu`` exports it, :func:`fmus.systemfmu.export.export_fmu`); for each, a second cold run under
``python -X importtime`` names the imports that cost the most; and the ClosedLoop's 9 s run,
cold, whose e_ef (thesis 7.31 over t in [1, 8] s, from its outputs ``x``, ``y``,
``traj.x_d``, ``traj.y_d``) must be ``parcosim run bench_circle_TCMDx``'s 0.4471702351989962 mm
(the k h clock; t + h gave issue 27's 0.4471702325699642, docs/master.md "The clock")::

    python -m benchmarks.cold_start                     # build, measure, print a table
    python -m benchmarks.cold_start --repeat 3 --json cold.json
    python -m benchmarks.cold_start --fmu-dir DIR       # FMUs already built there (names below)
    python -m benchmarks.cold_start --env NUMBA_DISABLE_JIT=1 --no-e-ef   # the start without numba's JIT

Run it from the repository (``python -m``: the checkout's packages build the FMUs).
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
BASELINE_DIR = HERE / "baseline_fmu"
#: The scene the ClosedLoop is exported from, and its e_ef [mm] (``parcosim run``).
SCENE = "bench_circle_TCMDx"
E_EF_MM = 0.4471702351989962
#: The CPU [s] an FMU's cold run may take over the C baseline's (issue 27, item 5).
ALLOWED_EXTRA_CPU = 1.0
#: FMU file names in ``--fmu-dir``, baseline first.
FMUS = ("LowPass", "PositionController", "FiveBarPlant", "ClosedLoop")
#: Environment variables that point at caches, each given a new empty folder per run.
CACHE_VARIABLES = ("HOME", "XDG_CACHE_HOME", "XDG_CONFIG_HOME", "XDG_DATA_HOME", "PARCOSIM_CACHE",
                   "NUMBA_CACHE_DIR", "PARCOSIM_COMPILED_CACHE", "MPLCONFIGDIR", "TMPDIR")

#: The child's program: the run as a user writes it; argv: fmu, stop time, output interval,
#: then "e_ef" to print the e_ef of a ClosedLoop's run.
CHILD = """
import json, sys
from fmpy import simulate_fmu
fmu, stop, interval = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
if sys.argv[4:] == ["e_ef"]:
    r = simulate_fmu(fmu, stop_time=stop, step_size=interval, output_interval=interval,
                     output=["x", "y", "traj.x_d", "traj.y_d"])
    import numpy as np
    t = r["time"]
    window = (t >= 1.0 - 1e-9) & (t <= 8.0 + 1e-9)
    ex, ey = (r["traj.x_d"] - r["x"])[window], (r["traj.y_d"] - r["y"])[window]
    print(json.dumps({"e_ef_mm": 1e3 * float(np.sqrt(np.mean(ex * ex + ey * ey))), "rows": int(len(t))}))
else:
    simulate_fmu(fmu, stop_time=stop, output_interval=interval)
print(json.dumps({"modules": sorted(sys.modules)}))
"""


@dataclass
class ColdRun:
    """One cold run of one FMU: CPU (user + sys) and wall [s], and what the child printed."""

    fmu: str
    cpu_s: float
    wall_s: float
    user_s: float
    sys_s: float
    output: dict = field(default_factory=dict)


def build_baseline(out: Path) -> Path:
    """Compile the C baseline against the FMI 2.0 headers fmpy ships and zip it as
    ``out/LowPass.fmu``."""
    import fmpy

    headers = Path(fmpy.__file__).resolve().parent / "c-code"
    if not (headers / "fmi2Functions.h").is_file():
        raise FileNotFoundError(f"fmpy's FMI 2.0 headers are not in {headers}")
    compiler = shutil.which(os.environ.get("CC", "")) or shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise RuntimeError("no C compiler (cc or gcc) for the baseline FMU")
    with tempfile.TemporaryDirectory(prefix="cold_baseline_") as tmp:
        library = Path(tmp) / "lowpass.so"
        subprocess.run([compiler, "-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-fPIC", "-shared",
                        f"-I{headers}", str(BASELINE_DIR / "lowpass.c"), "-o", str(library), "-lm"], check=True)
        path = out / "LowPass.fmu"
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
            z.write(BASELINE_DIR / "modelDescription.xml", "modelDescription.xml")
            z.write(library, "binaries/linux64/lowpass.so")
            z.write(BASELINE_DIR / "lowpass.c", "sources/lowpass.c")
    return path


def build_fmus(out: Path) -> dict:
    """Build the baseline and parcosim's three FMUs into ``out``: name -> path."""
    from fmus.export.build import build_fmu
    from fmus.systemfmu.export import export_fmu
    from scenarios.scenes.catalogue import get_scene

    out.mkdir(parents=True, exist_ok=True)
    paths = {"LowPass": build_baseline(out)}
    for model in ("PositionController", "FiveBarPlant"):
        paths[model] = build_fmu(model, out)
    paths["ClosedLoop"] = export_fmu(get_scene(SCENE).system, out / "ClosedLoop.fmu")
    return paths


#: Variables given to every child beside the cache folders (``--env``).
EXTRA_ENV = {}


def cold_environment(scratch: Path) -> dict:
    """The parent's environment with every cache variable at a new empty folder under
    ``scratch``, nothing of this checkout on the Python path, and :data:`EXTRA_ENV`."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"} | EXTRA_ENV
    for name in CACHE_VARIABLES:
        folder = scratch / name.lower()
        folder.mkdir()
        env[name] = str(folder)
    return env


def cold_run(fmu: Path, stop_time: float = 0.01, interval: float = 1e-3, extra=(), python_flags=()) -> ColdRun:
    """``fmpy.simulate_fmu`` of ``fmu`` in a fresh process with empty caches (module doc).

    Raises
    ------
    RuntimeError
        The child failed; the message holds its stderr's end.
    """
    with tempfile.TemporaryDirectory(prefix="cold_start_") as scratch:
        scratch = Path(scratch)
        work = scratch / "cwd"
        work.mkdir()
        command = [sys.executable, *python_flags, "-c", CHILD, str(Path(fmu).resolve()), repr(stop_time),
                   repr(interval), *extra]
        start = time.perf_counter()
        child = subprocess.Popen(command, cwd=work, env=cold_environment(scratch), stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True)
        stdout, stderr = _communicate(child)
        wall = time.perf_counter() - start
    usage = child.rusage
    if child.returncode != 0:
        raise RuntimeError(f"cold run of {fmu} failed ({child.returncode}): {stderr[-2000:]}")
    output = {}
    for line in stdout.splitlines():
        if line.startswith("{"):
            output.update(json.loads(line))
    output["stderr"] = stderr
    return ColdRun(Path(fmu).stem, usage.ru_utime + usage.ru_stime, wall, usage.ru_utime, usage.ru_stime, output)


def _communicate(child: subprocess.Popen) -> tuple:
    """The child's stdout and stderr; its resource usage (that child alone, from ``wait4``)
    is left on ``child.rusage``."""
    import threading

    chunks = {}
    readers = [threading.Thread(target=lambda s=s, n=n: chunks.__setitem__(n, s.read()))
               for n, s in (("out", child.stdout), ("err", child.stderr))]
    for reader in readers:
        reader.start()
    _, status, child.rusage = os.wait4(child.pid, 0)
    for reader in readers:
        reader.join()
    child.returncode = os.waitstatus_to_exitcode(status)
    return chunks["out"], chunks["err"]


def top_imports(importtime_stderr: str, count: int = 8) -> list:
    """The ``count`` costliest imports of a ``python -X importtime`` log: (module, cumulative
    µs, self µs), among the modules imported by the run itself or by fmpy's loading of the FMU
    (nesting level at most 2), most cumulative time first."""
    rows = []
    for line in importtime_stderr.splitlines():
        if not line.startswith("import time:") or "cumulative" in line:
            continue
        own, cumulative, name = line[len("import time:"):].split("|")
        depth = (len(name) - len(name.lstrip(" ")) - 1) // 2
        if depth <= 2:
            rows.append((name.strip(), int(cumulative), int(own)))
    return sorted(rows, key=lambda r: -r[1])[:count]


def measure(paths: dict, repeat: int) -> dict:
    """Each FMU's cold runs (the one of least CPU of ``repeat``), its extra CPU over the
    baseline's, its top imports, and the modules its run left loaded."""
    report = {}
    for name in FMUS:
        runs = [cold_run(paths[name]) for _ in range(repeat)]
        best = min(runs, key=lambda r: r.cpu_s)
        traced = cold_run(paths[name], python_flags=("-X", "importtime"))
        report[name] = {"cpu_s": best.cpu_s, "wall_s": best.wall_s, "user_s": best.user_s, "sys_s": best.sys_s,
                        "cpu_all_s": [r.cpu_s for r in runs], "wall_all_s": [r.wall_s for r in runs],
                        "top_imports": top_imports(traced.output["stderr"]),
                        "heavy_modules": heavy_modules(best.output.get("modules", []))}
    for name in FMUS:
        report[name]["extra_cpu_s"] = report[name]["cpu_s"] - report["LowPass"]["cpu_s"]
        report[name]["extra_wall_s"] = report[name]["wall_s"] - report["LowPass"]["wall_s"]
    return report


#: Packages a parcosim FMU started with its default parameters should not need.
HEAVY = ("control", "scipy.signal", "numba", "matplotlib", "sympy", "scipy.stats")


def heavy_modules(modules) -> list:
    """The :data:`HEAVY` packages among ``modules`` (loaded module names)."""
    return [h for h in HEAVY if h in modules]


def closed_loop_e_ef(path: Path) -> dict:
    """The ClosedLoop's 9 s run, cold: e_ef [mm], its relative deviation from :data:`E_EF_MM`,
    CPU and wall [s]."""
    run = cold_run(path, stop_time=9.0, interval=1e-3, extra=("e_ef",))
    e_ef = run.output["e_ef_mm"]
    return {"e_ef_mm": e_ef, "relative_deviation": abs(e_ef - E_EF_MM) / E_EF_MM, "rows": run.output["rows"],
            "cpu_s": run.cpu_s, "wall_s": run.wall_s}


def print_report(report: dict, loop: dict | None) -> None:
    print(f"{'FMU':20s} {'CPU s':>7s} {'wall s':>7s} {'CPU - C':>8s} {'within 1 s':>10s}  heavy modules loaded")
    for name in FMUS:
        r = report[name]
        ok = "yes" if r["extra_cpu_s"] <= ALLOWED_EXTRA_CPU else "NO"
        print(f"{name:20s} {r['cpu_s']:7.2f} {r['wall_s']:7.2f} {r['extra_cpu_s']:8.2f} {ok:>10s}  "
              f"{', '.join(r['heavy_modules']) or '-'}")
    for name in FMUS:
        print(f"\n{name}: costliest imports (cumulative ms, self ms)")
        for module, cumulative, own in report[name]["top_imports"]:
            print(f"  {module:50s} {cumulative / 1e3:8.1f} {own / 1e3:8.1f}")
    if loop:
        print(f"\nClosedLoop 9 s run, cold: e_ef = {loop['e_ef_mm']!r} mm (relative deviation "
              f"{loop['relative_deviation']:.2e} from {E_EF_MM!r}; {loop['rows']} rows), "
              f"CPU {loop['cpu_s']:.2f} s, wall {loop['wall_s']:.2f} s")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmu-dir", type=Path, help="FMUs already built there (LowPass.fmu, "
                        "PositionController.fmu, FiveBarPlant.fmu, ClosedLoop.fmu); default: build them")
    parser.add_argument("--repeat", type=int, default=1, help="cold runs per FMU; the least CPU is reported")
    parser.add_argument("--no-e-ef", action="store_true", help="skip the ClosedLoop's 9 s run")
    parser.add_argument("--json", type=Path, help="also write the figures to this file")
    parser.add_argument("--env", action="append", default=[], metavar="NAME=VALUE",
                        help="set a variable in every child (e.g. NUMBA_DISABLE_JIT=1: what the start costs "
                             "without numba's compilation)")
    args = parser.parse_args(argv)
    for assignment in args.env:
        name, equals, value = assignment.partition("=")
        if not equals or not name:
            raise SystemExit(f"--env {assignment!r}: write NAME=VALUE")
        EXTRA_ENV[name] = value
    with tempfile.TemporaryDirectory(prefix="cold_fmus_") as tmp:
        if args.fmu_dir:
            paths = {name: args.fmu_dir / f"{name}.fmu" for name in FMUS}
            missing = [str(p) for p in paths.values() if not p.is_file()]
            if missing:
                raise SystemExit(f"--fmu-dir {args.fmu_dir}: no {', '.join(missing)}")
        else:
            paths = build_fmus(Path(tmp))
        report = measure(paths, args.repeat)
        loop = None if args.no_e_ef else closed_loop_e_ef(paths["ClosedLoop"])
    print_report(report, loop)
    if EXTRA_ENV:
        print(f"children's extra environment: {EXTRA_ENV}")
    if args.json:
        args.json.write_text(json.dumps({"fmus": report, "closed_loop_9s": loop, "repeat": args.repeat,
                                         "env": EXTRA_ENV,
                                         "python": sys.version.split()[0], "date_utc":
                                         time.strftime("%Y-%m-%d %H:%M", time.gmtime())}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
