"""The closed loop's speed: a scene through the master, in process and through the FMUs,
beside the floor of pass-through FMUs in the same topology, measured in one run.

    python benchmarks/bench_master.py [--quick] [--repeats N] [--scene NAME] [--drives-in-plant N] [--fmu-dir DIR]
                                      [--json FILE] [--cases inprocess,floor_inprocess,...]

Four cases run the same system (same instances, connections, recorded signals and step
count, Gauss-Seidel):

* ``in-process``: ``simulate(system, mode="inprocess")``, the slave objects called directly,
  those whose model has a compiled step through it (:mod:`fmus.cosim.segments`);
* ``in-process, Python slaves``: the same with every slave's Python ``do_step`` (the stepper's
  kernel segments off: :func:`python_slaves`), the in-process path before them;
* ``through FMUs``: ``simulate(system, mode="fmu")``, the built FMUs through fmpy's raw
  ``fmi2SetReal/fmi2DoStep/fmi2GetReal`` (real FMUs in ``--fmu-dir``, default ``fmus/build``,
  built when missing or stale);
* ``compiled loop``: ``simulate(system, mode="compiled")``, the whole step loop compiled
  (:mod:`fmus.cosim.compiled`; compiled or loaded from its cache in the warm-up, ``setup`` includes
  loading it);
* ``floor, in-process`` and ``floor, through FMUs``: the same, with every model replaced by its
  pass-through stand-in (:mod:`passthrough`: same variables, a ``doStep`` that only copies),
  built into a temporary directory at start.  The FMU floor is what the master, pythonfmu and
  the FMI calls cost alone; the real time minus the floor is our models' compute.

Each case runs once untimed first (imports, file extraction, the controller's table); then ``--repeats`` rounds run every case in turn (so load
from elsewhere on the machine hits all cases alike) and the median over the rounds is printed.

Figures: ``wall`` is ``Result.wall_s`` (initialisation and every step; loading the FMUs and
instantiating the slaves is outside it, in ``setup``); the real-time factor is simulated time /
wall; ``µs/step`` is the stepping alone, timed between the master's first and last progress
calls (about 1 % and 100 % of the steps), also given for the best round and in CPU time of the
thread (``time.thread_time``: not counting the time other jobs on a shared machine hold the
CPU, so steadier there; cache effects of their load remain).

The machine's speed: :mod:`machine_probe` times a fixed C workload before and after every
round (``probe_s`` in the JSON).  This machine's cores run the same code at two speeds that
alternate every few seconds (1.5-1.8x apart, invisible to the load average and to CPU time), so
a second table gives each case's median over the rounds whose two probes are both within
:data:`machine_probe.TOLERANCE` of the run's fastest: the machine at full speed.

Where the time goes: each round also runs every case but the in-process one with kernel segments
(which has one C call a step, nothing per instance to time) and the compiled loop once more with
timers (not in the table above): every instance's inputs set, step and outputs read as the master's
stepper calls them
(``fmus.cosim.stepper.member_calls``: in process the slave's attributes and its ``do_step``; through
FMUs ``fmi2SetReal``, ``fmi2DoStep``, ``fmi2GetReal``), and inside the step the slave's own
Python ``do_step`` (``fmus.slave.base.GuardedSlave``; the FMUs loaded in this process share that
module, so this also times the Python side of an FMU's ``fmi2DoStep``).  The timers wrap
``fmus.cosim.stepper.member_calls`` and ``GuardedSlave.do_step`` for the duration of the run and add
about 0.3 µs a call.

The in-process floor runs through the unchanged ``simulate(mode="inprocess")``:
:func:`passthrough.registered` adds the pass-through classes to ``fmus.export.build.SLAVES`` for the
duration of the run.

Goals (issue 5): >= 10x faster than real time through the FMUs, >= 50x in process; (issue 16)
>= 200x for the compiled loop (goal 500x).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from fmus.cosim.master import simulate  # noqa: E402
import passthrough  # noqa: E402
from machine_probe import TOLERANCE, Probe, quiet_rounds, spread  # noqa: E402

GOAL_RTF = {"fmu": 10.0, "inprocess": 50.0, "compiled": 200.0}
QUICK_STOP_TIME = 2.0
WARMUP_STOP_TIME = 0.05
CASES = (  # key, label, mode, floor
    ("inprocess", "in-process", "inprocess", False),
    ("inprocess_python", "in-process, Python slaves", "inprocess", False),
    ("fmu", "through FMUs", "fmu", False),
    ("floor_inprocess", "floor (pass-through), in-process", "inprocess", True),
    ("floor_fmu", "floor (pass-through), through FMUs", "fmu", True),
    ("compiled", "compiled loop", "compiled", False),
)
#: Cases timed per component (the compiled loop has no per-instance calls to time).
TIMED_CASES = ("inprocess_python", "fmu", "floor_inprocess", "floor_fmu")


def run_case(system, mode, fmu_dir, classes=None, python=False) -> dict:
    """One run: setup, wall, µs per step (stepping only, wall clock and CPU time), order;
    ``python``: the in-process slaves all through their Python ``do_step``."""
    stamps = []
    clock, cpu = time.perf_counter, time.thread_time

    def progress(fraction):
        stamps.append((fraction, clock(), cpu()))

    registration = passthrough.registered(classes) if (classes and mode == "inprocess") else _nothing()
    with registration, (python_slaves() if python else _nothing()):
        start = clock()
        result = simulate(system, mode=mode, fmu_dir=fmu_dir, progress=progress)
        total = clock() - start
    if result.error is not None:
        raise RuntimeError(f"{mode} run stopped: {result.error}")
    steps = system.steps
    if len(stamps) >= 2 and stamps[-1][0] > stamps[0][0]:
        (f0, t0, c0), (f1, t1, c1) = stamps[0], stamps[-1]
        n = (f1 - f0) * steps
        step_s, cpu_s = (t1 - t0) / n, (c1 - c0) / n
    else:
        step_s = cpu_s = result.wall_s / max(steps, 1)
    return {"total_s": total, "wall_s": result.wall_s, "setup_s": total - result.wall_s,
            "us_per_step": 1e6 * step_s, "cpu_us_per_step": 1e6 * cpu_s,
            "rtf": system.stop_time / result.wall_s, "order": result.order, "result": result,
            "load": os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")}


@contextmanager
def _nothing():
    yield


@contextmanager
def python_slaves():
    """Within the block, ``simulate(mode="inprocess")`` steps every slave through its Python
    ``do_step`` (its stepper without kernel segments)."""
    from fmus.cosim import master

    original = master.Stepper

    class PythonStepper(original):
        def __init__(self, *args, kernels=None, **kwargs):
            super().__init__(*args, **kwargs)

    master.Stepper = PythonStepper
    try:
        yield
    finally:
        master.Stepper = original


# --- per-component breakdown ---------------------------------------------------------------

METHODS = ("set_inputs", "do_step", "get_outputs")
#: What the breakdown reports per instance: the master's three calls, and inside do_step the
#: slave's own Python ``do_step`` (fmus.slave.base.GuardedSlave.do_step: validation and the model).
CELLS = METHODS + ("python_do_step",)


@contextmanager
def timed_instances():
    """Time every instance's inputs set, step and outputs read as the master's stepper calls
    them, and the slave's own Python ``do_step``, while the block runs.

    ``fmus.cosim.stepper.member_calls`` (what the stepper calls per instance: the in-process slaves'
    attributes moved directly, an FMU's ``set_inputs``/``do_step``/``get_outputs``) is wrapped
    so that each call is timed; ``fmus.slave.base.GuardedSlave.do_step`` (the base of every slave,
    shared by the FMUs loaded in this process: they import ``fmus.slave.base`` from its module
    cache) is wrapped at class level.  Both are restored afterwards.  Yields a dict instance
    name -> cell -> [calls, seconds].
    """
    from fmus.slave import base as guarded
    from fmus.cosim import stepper

    original_member_calls = stepper.member_calls
    original_do_step = guarded.GuardedSlave.__dict__["do_step"]
    clock = time.perf_counter
    table = {}

    def member_calls(inst, in_slots, out_slots):
        pull, step, read, source, out, owner = original_member_calls(inst, in_slots, out_slots)
        cells = table.setdefault(inst.name, {})
        cells.update({m: [0, 0.0] for m in METHODS})
        timed_pull = None if pull is None else _timed(pull, cells["set_inputs"])
        return (timed_pull, _timed(step, cells["do_step"]), _timed(read, cells["get_outputs"]), source, out, owner)

    def do_step(self, current_time, step_size):
        t0 = clock()
        ok = original_do_step(self, current_time, step_size)
        cells = table.get(self.instance_name)
        if cells is not None:
            cell = cells.setdefault("python_do_step", [0, 0.0])
            cell[1] += clock() - t0
            cell[0] += 1
        return ok

    stepper.member_calls = member_calls
    guarded.GuardedSlave.do_step = do_step
    try:
        yield table
    finally:
        stepper.member_calls = original_member_calls
        guarded.GuardedSlave.do_step = original_do_step


def _timed(function, cell):
    """``function`` timed into ``cell`` ([calls, seconds])."""
    clock = time.perf_counter

    def timed(*args):
        t0 = clock()
        out = function(*args)
        cell[1] += clock() - t0
        cell[0] += 1
        return out
    return timed


def timer_overhead(n=100_000) -> tuple:
    """(µs a timed call adds in all, µs of it inside the timed window), on a no-op."""
    def noop(t, h):
        pass

    cell = [0, 0.0]
    timed = _timed(noop, cell)
    best = (float("inf"), float("inf"))
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(n):
            noop(0.0, 1.0)
        t1 = time.perf_counter()
        cell[1] = 0.0
        for _ in range(n):
            timed(0.0, 1.0)
        t2 = time.perf_counter()
        call = (t1 - t0) / n
        best = min(best, (1e6 * ((t2 - t1) / n - call), 1e6 * (cell[1] / n - call)))
    return best


def breakdown(system, mode, fmu_dir, classes=None, python=False) -> dict:
    """Per-instance µs per communication step in each method, and the rest of the loop."""
    with timed_instances() as table:
        run = run_case(system, mode, fmu_dir, classes, python)
    steps = system.steps
    # get_outputs is also called once after initialisation (1 call in steps + 1): ignored.
    per = {name: {c: 1e6 * cells.get(c, [0, 0.0])[1] / steps for c in CELLS} for name, cells in table.items()}
    for name, cells in table.items():
        if cells.get("python_do_step", [0])[0] == 0:   # a slave that overrides do_step: not seen
            per[name]["python_do_step"] = float("nan")
    accounted = sum(v[m] for v in per.values() for m in METHODS)
    return {"components": per, "us_per_step": run["us_per_step"],
            "rest_us": run["us_per_step"] - accounted, "order": run["order"], "load": run["load"]}


# --- reporting ----------------------------------------------------------------------------

def machine() -> dict:
    """CPU, Python, commit, locally modified tracked files, load average."""
    def git(*args):
        try:
            return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, timeout=20).stdout
        except (OSError, subprocess.SubprocessError):
            return ""

    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    dirty = [line[3:] for line in git("status", "--porcelain", "--untracked-files=no").splitlines() if line]
    return {"cpu": cpu, "cpus": os.cpu_count(), "python": platform.python_version(),
            "commit": git("rev-parse", "--short", "HEAD").strip(), "modified_tracked_files": dirty,
            "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg") else None}


def _median_breakdown(rounds: list) -> dict:
    """Cell-wise median of several :func:`breakdown` results."""
    names = rounds[0]["components"]
    return {"components": {n: {c: statistics.median(r["components"][n][c] for r in rounds) for c in CELLS}
                           for n in names},
            "us_per_step": statistics.median(r["us_per_step"] for r in rounds),
            "rest_us": statistics.median(r["rest_us"] for r in rounds),
            "order": rounds[0]["order"]}


SHORT = {"inprocess": "in-process", "fmu": "FMU", "floor_inprocess": "floor in-proc", "floor_fmu": "floor FMU"}


def report(scene_name, system, runs, breakdowns, info_before, info_after, overhead) -> str:
    """The tables, as Markdown."""
    repeats = len(next(iter(runs.values())))
    med = {k: {q: statistics.median(r[q] for r in rs) for q in ("wall_s", "us_per_step", "cpu_us_per_step", "rtf", "setup_s")}
           for k, rs in runs.items()}
    out = [f"{scene_name}: {system.stop_time:g} s simulated, {system.steps} steps of "
           f"{1e3 * system.step:g} ms, {len(system.components)} instances, Gauss-Seidel; "
           f"median of {repeats} interleaved rounds",
           f"machine: {info_before['cpu']}, {info_before['cpus']} CPUs, Python {info_before['python']}, "
           f"commit {info_before['commit']}"
           + (f" + local edits to {', '.join(info_before['modified_tracked_files'])}"
              if info_before["modified_tracked_files"] else "")]
    if info_before["load_average"]:
        la0, la1 = info_before["load_average"], info_after["load_average"]
        out.append(f"load average (1/5/15 min): before {la0[0]:.2f}/{la0[1]:.2f}/{la0[2]:.2f}, "
                   f"after {la1[0]:.2f}/{la1[1]:.2f}/{la1[2]:.2f}")
    out += ["", "| case | wall [s] | real-time factor | µs/step | µs/step, best round | µs/step, CPU time "
            "| setup [s] | load (1 min) | goal |", "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
    for key, label, mode, floor in (c for c in CASES if c[0] in med):
        m = med[key]
        goal = ""
        if not floor:
            g = GOAL_RTF[mode]
            goal = f">= {g:g}x: {'met' if m['rtf'] >= g else 'not met'}"
        best = min(r["us_per_step"] for r in runs[key])
        load = statistics.median(r["load"] for r in runs[key])
        out.append(f"| {label} | {m['wall_s']:.2f} | {m['rtf']:.1f}x | {m['us_per_step']:.0f} | {best:.0f} | "
                   f"{m['cpu_us_per_step']:.0f} | {m['setup_s']:.2f} | {load:.1f} | {goal} |")
    out += full_speed(runs)
    us = {k: med[k]["us_per_step"] for k in med}
    best = {k: min(r["us_per_step"] for r in rs) for k, rs in runs.items()}
    rows = (("our compute through FMUs (FMUs - FMU floor)", "fmu", "floor_fmu"),
            ("our compute in process (in-process - in-process floor)", "inprocess", "floor_inprocess"),
            ("FMI cost alone (FMU floor - in-process floor)", "floor_fmu", "floor_inprocess"),
            ("FMUs - in-process (real models)", "fmu", "inprocess"))
    out += ["", "| µs per step | medians | best rounds |", "|---|---:|---:|"]
    for label, a, b in (r for r in rows if r[1] in us and r[2] in us):
        out.append(f"| {label} | {us[a] - us[b]:.0f} | {best[a] - best[b]:.0f} |")
    cpu = {k: statistics.median(r["cpu_us_per_step"] for r in rs) for k, rs in runs.items()}
    for label, a, b in (("FMUs / FMU floor (goal <= 1.3)", "fmu", "floor_fmu"),
                        ("in-process / in-process floor", "inprocess", "floor_inprocess"),
                        ("in-process with Python slaves / in-process", "inprocess_python", "inprocess")):
        if a in us and b in us:
            out.append(f"| {label}, ratio (CPU time: {cpu[a] / cpu[b]:.2f}) | {us[a] / us[b]:.2f} | "
                       f"{best[a] / best[b]:.2f} |")
    if "fmu" in us and "floor_fmu" in us:
        out.append(f"| share of the FMU step that is our compute | {100 * (us['fmu'] - us['floor_fmu']) / us['fmu']:.0f} % "
                   f"| {100 * (best['fmu'] - best['floor_fmu']) / best['fmu']:.0f} % |")
    for key in (k for k in ("fmu", "inprocess") if k in us):
        g = GOAL_RTF[key]
        out.append(f"| budget for {g:g}x {'through FMUs' if key == 'fmu' else 'in process'} "
                   f"(now {us[key]:.0f}, best {best[key]:.0f}) | {1e6 * system.step / g:.0f} | |")
    if breakdowns:
        models = {c.name: c.model for c in system.components}
        out += ["", "Where the time goes, µs per communication step (extra runs with timers on, cell-wise "
                f"median over the rounds; a timer adds about {max(overhead[0], 0):.2f} µs a call). "
                "**model**: the slave's own Python `do_step` (the base's checks and the model's step); "
                "**call**: the rest of the master's doStep call (in process: one method call; through "
                "FMUs: ctypes, pythonfmu's C wrapper, the GIL); **set/get**: inputs written and outputs "
                "read (in process: attributes; through FMUs: fmi2SetReal + fmi2GetReal); **master**: the "
                "loop itself (copies between slots, the recorded row)."]
        for title, pair in (("Real models", ("inprocess_python", "fmu")),
                            ("Pass-through floor", ("floor_inprocess", "floor_fmu"))):
            keys = [k for k in pair if k in breakdowns]     # both, or the one --cases ran
            if not keys:
                continue
            sides = ["in-process" if "inprocess" in k else "FMU" for k in keys]   # Python slaves
            out += ["", f"{title}:", "",
                    "| instance | model | " + " | ".join(f"{s} model | {s} call | {s} set/get" for s in sides) + " |",
                    "|---|---|" + "---:|---:|---:|" * len(keys)]
            totals = {k: [0.0, 0.0, 0.0] for k in keys}
            for n in breakdowns[keys[0]]["order"]:
                cells = []
                for k in keys:
                    c = breakdowns[k]["components"][n]
                    parts = (c["python_do_step"], c["do_step"] - c["python_do_step"],
                             c["set_inputs"] + c["get_outputs"])
                    totals[k] = [x + y for x, y in zip(totals[k], parts)]
                    cells.append(" | ".join(f"{x:.1f}" for x in parts))
                out.append(f"| {n} | {models[n]} | " + " | ".join(cells) + " |")
            out.append("| **sum** | | " + " | ".join(" | ".join(f"{x:.1f}" for x in totals[k]) for k in keys) + " |")
            out.append("| master | | " + " | ".join(f"{breakdowns[k]['rest_us']:.1f} | |" for k in keys) + " |")
            out.append("| **total** | timers on | "
                       + " | ".join(f"{breakdowns[k]['us_per_step']:.1f} | |" for k in keys) + " |")
    return "\n".join(out)


def full_speed(runs) -> list:
    """The table of the rounds run with the machine at full speed (:mod:`machine_probe`: the
    probes before and after the round within its tolerance of the run's fastest), as lines."""
    probes = [r["probe_s"] for rs in runs.values() for r in rs if "probe_s" in r]
    if not probes:
        return []
    s = spread(probes)
    fastest = s["fastest_s"]
    out = ["", f"The machine's speed (benchmarks/machine_probe.py, a fixed C workload before and after each round): "
           f"fastest {1e3 * fastest:.2f} ms, median {1e3 * s['median_s']:.2f}, slowest {1e3 * s['slowest_s']:.2f} "
           f"(slowest / fastest {s['ratio']:.2f}). Rounds at full speed: both probes within "
           f"{TOLERANCE:g}x of the fastest.", "",
           "| case | rounds at full speed | real-time factor, their median | µs/step, their median | goal |",
           "|---|---:|---:|---:|---|"]
    for key, label, mode, floor in (c for c in CASES if c[0] in runs):
        rs = runs[key]
        fastest_rounds = [rs[i] for i in quiet_rounds([r["probe_s"] for r in rs], fastest_s=fastest)]
        if not fastest_rounds:
            out.append(f"| {label} | 0 of {len(rs)} | | | |")
            continue
        rtf = statistics.median(r["rtf"] for r in fastest_rounds)
        goal = "" if floor else f">= {GOAL_RTF[mode]:g}x: {'met' if rtf >= GOAL_RTF[mode] else 'not met'}"
        out.append(f"| {label} | {len(fastest_rounds)} of {len(rs)} | {rtf:.1f}x | "
                   f"{statistics.median(r['us_per_step'] for r in fastest_rounds):.0f} | {goal} |")
    return out


def measure(system, repeats: int, fmu_dir=None, with_breakdown: bool = True, keys=None):
    """Every case of :data:`CASES` (or those of ``keys``) on ``system``: a warm-up, then
    ``repeats`` interleaved rounds.

    Returns (runs, timed, timer overhead, machine before, machine after): ``runs[key]`` the
    :func:`run_case` of each round, ``timed[key]`` the :func:`breakdown` of each round (empty
    without ``with_breakdown``).
    """
    from fmus.export.build import ensure_built

    cases = [c for c in CASES if keys is None or c[0] in keys]
    floor_system = passthrough.passthrough_system(system)
    models = sorted({c.model for c in system.components})
    tmp = Path(tempfile.mkdtemp(prefix="parcosim_bench_master_"))
    try:
        floor_dir = tmp / "fmus"
        if any(floor and mode == "fmu" for _, _, mode, floor in cases):
            print(f"building {len(models)} pass-through FMUs ...", file=sys.stderr)
            passthrough.build_fmus(models, floor_dir)
        classes = passthrough.load_classes(models, tmp / "src")
        if any(mode == "fmu" and not floor for _, _, mode, floor in cases):
            ensure_built(models, fmu_dir)   # build now if missing or stale, not in a timed run

        def case(key, stop=None, timed=False):
            _, _, mode, floor = next(c for c in CASES if c[0] == key)
            s = floor_system if floor else system
            if stop is not None:
                s = replace(s, stop_time=stop)
            run = breakdown if timed else run_case
            return run(s, mode, floor_dir if floor else fmu_dir, classes if floor else None, key == "inprocess_python")

        print("warm-up ...", file=sys.stderr)
        warm = {key: case(key, WARMUP_STOP_TIME) for key, *_ in cases}
        for key in ("inprocess", "fmu"):
            if key in warm and f"floor_{key}" in warm and warm[f"floor_{key}"]["order"] != warm[key]["order"]:
                raise RuntimeError(f"the floor steps in another order: {warm['floor_' + key]['order']} "
                                   f"vs {warm[key]['order']}")
        overhead = timer_overhead()

        info_before = machine()
        probe = Probe()
        runs = {key: [] for key, *_ in cases}
        timed = {key: [] for key, *_ in cases}
        for r in range(repeats):
            for key, *_ in cases:
                before = probe()
                runs[key].append(case(key))
                runs[key][-1]["probe_s"] = (before, probe())
            if with_breakdown:
                for key in TIMED_CASES:
                    if key in timed:
                        timed[key].append(case(key, timed=True))
            print(f"round {r + 1}/{repeats}: " + ", ".join(
                f"{k} {runs[k][-1]['us_per_step']:.0f} µs" for k in runs), file=sys.stderr)
        info_after = machine()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return runs, timed, overhead, info_before, info_after


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="bench_circle_TCMDx", help="scene name (default bench_circle_TCMDx)")
    ap.add_argument("--quick", action="store_true", help=f"run {QUICK_STOP_TIME:g} s of the scene, not all of it")
    ap.add_argument("--repeats", type=int, default=5, help="timed rounds (default 5); the median is printed")
    ap.add_argument("--fmu-dir", type=Path, default=None,
                    help="directory of the real FMUs (default fmus/build; built when missing or stale)")
    ap.add_argument("--no-breakdown", action="store_true", help="skip the timed per-component runs")
    ap.add_argument("--cases", default=None,
                    help="comma-separated cases to run (default all: " + ",".join(c[0] for c in CASES) + ")")
    ap.add_argument("--json", type=Path, default=None, help="also write every measurement to this file")
    ap.add_argument("--drives-in-plant", type=int, default=None, metavar="N",
                    help="the scene with its drives inside the plant, RK4 N steps per sample (docs/actuated.md)")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error("--repeats must be >= 1")
    keys = None if args.cases is None else tuple(args.cases.split(","))
    unknown = sorted(set(keys or ()) - {c[0] for c in CASES})
    if unknown:
        ap.error(f"--cases: unknown {', '.join(unknown)}; valid: {', '.join(c[0] for c in CASES)}")

    from scenarios.scenes.catalogue import get_scene
    from scenarios.scenes.transforms import drives_in_plant

    scene = get_scene(args.scene)
    if args.drives_in_plant is not None:
        scene = drives_in_plant(scene, substeps=args.drives_in_plant)
        args.scene += f", drives in plant x{args.drives_in_plant}"
    system = scene.system
    if args.quick:
        system = replace(system, stop_time=min(system.stop_time, QUICK_STOP_TIME))
    runs, timed, overhead, info_before, info_after = measure(system, args.repeats, args.fmu_dir,
                                                             not args.no_breakdown, keys)
    breakdowns = {} if args.no_breakdown else {k: _median_breakdown(v) for k, v in timed.items() if v}
    print(report(args.scene, system, runs, breakdowns, info_before, info_after, overhead))
    if args.json is not None:
        payload = {"scene": args.scene, "stop_time": system.stop_time, "steps": system.steps,
                   "repeats": args.repeats, "machine_before": info_before, "machine_after": info_after,
                   "timer_overhead_us": overhead,
                   "runs": {k: [{q: v for q, v in r.items() if q != "result"} for r in rs]
                            for k, rs in runs.items()},
                   "breakdown_rounds": timed, "breakdown_median": breakdowns}
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(payload, indent=1, default=list))
    return 0


if __name__ == "__main__":
    sys.exit(main())
