"""Speed of the native FMUs beside the pythonfmu ones, in other people's hosts (issue 28, item 6).

    python benchmarks/native_speed.py [--native-dir DIR] [--python-dir DIR] [--rounds 3] [--stop 11]
                                      [--master-only] [--without MODEL ...] [--loop-only]

The scene (``bench_circle_TCMDx``: plant, two drives, two current observers, derivator,
controller, trajectory) is exported per component (``fmus.ssp.export.export_ssp``, as ``parcosim
export-ssp --per-component`` does) twice: once with the native FMUs of ``--native-dir``
(``parcosim build --native``, built when not given), once with the pythonfmu FMUs of ``--python-dir`` (built there
when missing).  Each package then runs, side by side in one invocation, in:

* ``C host``: tests/native_host/host.c, libcosim's C API in a C program, stepping one step at
  a time (no CSV rows); the pythonfmu package there only with libpython preloaded
  (``LD_PRELOAD``: without it its FMUs cannot load, "undefined symbol: PyExc_ValueError");
* ``libcosimpy``: ``CosimExecution.from_ssp_file(...).simulate_until(stop)`` in a Python child;
* ``ecospy``: ``EcosSimulation(step, ssp_path).step(n)`` in a Python child, on one CPU (as
  ``fmus.ssp.run.simulate_ssp_ecos`` runs it);
* the same hosts on a floor package: as many instances of the C low-pass of
  benchmarks/baseline_fmu, chained, next to nothing to compute: what the host costs;
* our master, ``parcosim run --mode fmu`` (fmpy) and ``--mode fmu --native``
  (``fmus.native.run.native_system``: the models with a native FMU run as one, the others
  stay pythonfmu); its stepping CPU is that of a full run less that of a 2-step run, both
  after a first 2-step run (loading and initialising are inside ``simulate``); with
  ``--without MODEL``, also ``--native`` with those models left pythonfmu (what making them
  native gave, side by side).  ``--master-only``: our master's rows alone.
* the whole loop as one FMU, ``ClosedLoop``: the native one (``parcosim export-fmu SCENE
  OUT.fmu --native``) and the pythonfmu one (``export-fmu``), each in the C host (one slave,
  no connections; the pythonfmu one with libpython preloaded) and in fmpy (``FMU2Slave``:
  ``doStep`` and a read of ``x``, ``y`` per step, as a Python host steps it), with doSteps of
  its own 1 ms and of 10 ms (ten loop steps per doStep: the host's cost per call shared).
  With ``--loop-only`` only these rows are measured.  (The C host adds it with
  ``cosim_execution_create``: libcosim's default worker thread takes each step.  The native
  FMUs in three C hosts, libcosim's with ``numWorkerThreads="0"`` among them, side by side:
  benchmarks/native_c_hosts.py.)
* ``--per-component``: instead, the scene's per-component package of issue 26 (``parcosim
  export-ssp --per-component``: base step T / n, each sampled component's ``sample_phase``;
  n the export's trial's, from ``benchmarks/results/tools.json`` when stored there) with its
  pythonfmu FMUs and with native FMUs (``--native``: each instance's built with its
  parameters), in the C host, libcosimpy and ecospy; only these rows are measured.

Figures: CPU (user + system, all threads) of the stepping after the first step (loading,
initialising, which libcosim does in the first step, and that step are "setup") in
microseconds per simulated millisecond, the best of ``--rounds``; real-time factor =
simulated time / that CPU.  Written to ``benchmarks/results/native_speed.json`` and printed
as a markdown table (docs/benchmarks.md).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import sysconfig
import tempfile
import textwrap
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

SCENE = "bench_circle_TCMDx"
#: The kind of the floor package (:func:`floor_package`).
FLOOR = "floor: 8 C low-passes"
RESULTS = ROOT / "benchmarks" / "results" / "native_speed.json"

LIBCOSIMPY_CHILD = textwrap.dedent("""
    import json, sys, time
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    log_output_level(CosimLogLevel.ERROR)
    path, stop = sys.argv[1], float(sys.argv[2])
    c0 = time.process_time()
    execution = CosimExecution.from_ssp_file(path)
    first = execution.step()                   # libcosim initialises the FMUs here
    now = execution.status().current_time
    c1 = time.process_time()
    ok = first and execution.simulate_until(int(round(stop * 1e9)))
    c2 = time.process_time()
    print(json.dumps({"setup_cpu_s": c1 - c0, "cpu_s": c2 - c1, "timed_s": stop - now * 1e-9, "ok": bool(ok)}))
""")

ECOSPY_CHILD = textwrap.dedent("""
    import json, os, sys, time
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    from ecospy import EcosLib, EcosSimulation
    from fmus.ssp.export import PARAMETER_SET, read_ssp_experiment
    EcosLib.set_log_level("err")
    path, stop = sys.argv[1], float(sys.argv[2])
    step = read_ssp_experiment(path)[2]
    c0 = time.process_time()
    sim = EcosSimulation(step, ssp_path=path)
    ok = sim.init(0.0, PARAMETER_SET)
    sim.step(1)                                # as the other hosts: the first step is set-up
    c1 = time.process_time()
    sim.step(int(round(stop / step)) - 1)
    c2 = time.process_time()
    reached = sim.get_time()
    sim.terminate()
    sim.free()
    print(json.dumps({"setup_cpu_s": c1 - c0, "cpu_s": c2 - c1, "timed_s": stop - step,
                      "ok": bool(ok) and reached >= stop - step / 2}))
""")

FMPY_CHILD = textwrap.dedent("""
    import json, sys, time
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    path, stop, multiple = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
    c0 = time.process_time()
    md = read_model_description(path)
    step = multiple * float(md.defaultExperiment.stepSize)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path), modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="loop")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    outputs = [vr["x"], vr["y"]]
    fmu.doStep(0.0, step)                      # as the other hosts: the first step is set-up
    fmu.getReal(outputs)
    c1 = time.process_time()
    n = int(round(stop / step))
    for k in range(1, n):
        fmu.doStep(k * step, step)
        fmu.getReal(outputs)
    c2 = time.process_time()
    fmu.terminate()
    fmu.freeInstance()
    print(json.dumps({"setup_cpu_s": c1 - c0, "cpu_s": c2 - c1, "timed_s": stop - step, "ok": True}))
""")

MASTER_CHILD = textwrap.dedent("""
    import json, sys, time
    from fmus.cosim.master import simulate
    from scenarios.scenes.catalogue import get_scene
    import dataclasses
    scene, native, fmu_dir, stop = sys.argv[1], sys.argv[2] == "native", sys.argv[3], float(sys.argv[4])
    system = get_scene(scene).system
    if native:                                 # parcosim run --mode fmu --native
        from fmus.native.models import NATIVE
        from fmus.native.run import native_system
        for model in filter(None, sys.argv[5].split(",")):   # left pythonfmu
            NATIVE.pop(model)
        system = native_system(system, out_dir=fmu_dir)
    cpu = []
    # the stepping's CPU: a full run less a 2-step run, after a first run (builds, extractions)
    for length in (2 * system.step, 2 * system.step, stop):
        c0 = time.process_time()
        result = simulate(dataclasses.replace(system, stop_time=length), mode="fmu", fmu_dir=fmu_dir)
        cpu.append(time.process_time() - c0)
    print(json.dumps({"setup_cpu_s": cpu[1], "cpu_s": cpu[2] - cpu[1], "timed_s": stop - 2 * system.step,
                      "ok": bool(result.completed)}))
""")


def export_packages(work: Path, native_dir: Path, python_dir: Path, scene: str) -> dict:
    """The scene per component with each set of FMUs: kind ("native", "pythonfmu") -> .ssp."""
    from fmus.export.build import ensure_built
    from fmus.ssp.export import export_ssp
    from scenarios.scenes.catalogue import get_scene

    system = get_scene(scene).system
    models = sorted({c.model for c in system.components})
    python_fmus = ensure_built(models, python_dir)
    native_fmus = {m: native_dir / f"{m}.fmu" for m in models}
    packages = {"pythonfmu": export_ssp(system, work / "pythonfmu.ssp", fmus=python_fmus),
                FLOOR: floor_package(work, len(system.components), system.step)}
    missing = sorted(m for m, p in native_fmus.items() if not p.is_file())
    if missing:
        print(f"no native package: no native FMU of {missing} in {native_dir}", file=sys.stderr)
    else:
        packages["native"] = export_ssp(system, work / "native.ssp", fmus=native_fmus)
    part = subsystem(system, [c.name for c in system.components if c.model not in missing])
    if missing and part.components:
        label = ", ".join(c.name for c in part.components)
        packages[f"native: {label}"] = export_ssp(part, work / "part_native.ssp",
                                                  fmus={c.model: native_fmus[c.model] for c in part.components})
        packages[f"pythonfmu: {label}"] = export_ssp(part, work / "part_pythonfmu.ssp",
                                                     fmus={c.model: python_fmus[c.model] for c in part.components})
    return packages


def export_per_component_packages(work: Path, python_dir: Path, scene: str) -> dict:
    """The scene's per-component package (issue 26) with its pythonfmu FMUs and with native
    FMUs, at the n of the export's trial (stored by scenarios/studies/tools.py, else run):
    kind -> .ssp."""
    from scenarios.packaging.per_component import export_per_component
    from scenarios.scenes.catalogue import get_scene
    from scenarios.studies.tools import load_results

    stored = load_results().get(f"trial|{scene}|per-component")
    n = stored["substeps"] if stored else None
    return {kind: export_per_component(get_scene(scene), work / kind.replace(" ", "_") / f"{scene}.ssp", python_dir,
                                       substeps=n, native=kind.endswith("native"))
            for kind in ("per-component pythonfmu", "per-component native")}


def subsystem(system, names):
    """The components ``names`` of ``system`` and the connections between them (the inputs
    the others fed keep their start values): the part that has native FMUs."""
    import dataclasses

    keep = set(names)
    inside = [c for c in system.connections if c.source.split(".")[0] in keep and c.target.split(".")[0] in keep]
    return dataclasses.replace(system, components=tuple(c for c in system.components if c.name in keep),
                               connections=tuple(inside),
                               record=tuple(r for r in system.record if r.split(".")[0] in keep))


def floor_package(work: Path, count: int, step: float) -> Path:
    """``count`` instances of the C low-pass of benchmarks/baseline_fmu in a chain, as one
    package: what each host costs per instance and step with next to nothing to compute."""
    from benchmarks.cold_start import build_baseline
    from fmus.ssp.export import export_ssp
    from fmus.cosim.system import Component, Connection, System

    names = [f"lp{i}" for i in range(count)]
    system = System(components=tuple(Component(n, "LowPass") for n in names),
                    connections=tuple(Connection(f"{a}.y", f"{b}.u") for a, b in zip(names, names[1:])),
                    record=(f"{names[-1]}.y",), stop_time=1.0, step=step)
    (work / "floor").mkdir(exist_ok=True)
    return export_ssp(system, work / "floor.ssp", fmus={"LowPass": build_baseline(work / "floor")})


def libpython() -> str | None:
    path = Path(sysconfig.get_config_var("LIBDIR") or "") / (sysconfig.get_config_var("LDLIBRARY") or "")
    return str(path) if path.name.startswith("libpython") and path.is_file() else None


def run_c_host(program: Path, package: Path, stop: float, work: Path, preload: str | None = None) -> dict:
    from tests.native_host.host import config_text, run_host

    env = {**os.environ, "LD_PRELOAD": preload} if preload else None
    run = run_host(program, work, config_text(stop, ssp=package, every=0), env=env)
    return {"setup_cpu_s": run.number("setup_cpu_s"), "cpu_s": run.number("cpu_s"), "timed_s": run.number("timed_s"),
            "ok": abs(run.number("simulated_s") - stop) < 1e-9, "libpython_mapped": int(run.report["libpython_mapped"])}


def export_loops(work: Path, scene: str) -> dict:
    """The scene's ClosedLoop FMUs: kind ("ClosedLoop native", "ClosedLoop pythonfmu") -> .fmu."""
    from fmus.systemfmu.export import export_fmu
    from fmus.native.loopbuild import export_native_fmu
    from scenarios.scenes import get_scene

    system = get_scene(scene).system
    return {"ClosedLoop native": export_native_fmu(system, work / "loop_native" / "ClosedLoop.fmu"),
            "ClosedLoop pythonfmu": export_fmu(system, work / "loop_pythonfmu" / "ClosedLoop.fmu")}


def run_c_host_loop(program: Path, fmu: Path, stop: float, work: Path, preload: str | None = None,
                    multiple: int = 1) -> dict:
    """The C host stepping one ClosedLoop FMU at ``multiple`` of its communication step, no CSV rows."""
    from fmpy import read_model_description
    from tests.native_host.host import config_text, run_host

    step = multiple * float(read_model_description(str(fmu)).defaultExperiment.stepSize)
    env = {**os.environ, "LD_PRELOAD": preload} if preload else None
    run = run_host(program, work, config_text(stop, step=step, slaves=[("loop", fmu)], every=0), env=env)
    return {"setup_cpu_s": run.number("setup_cpu_s"), "cpu_s": run.number("cpu_s"), "timed_s": run.number("timed_s"),
            "ok": abs(run.number("simulated_s") - stop) < 1e-9, "libpython_mapped": int(run.report["libpython_mapped"])}


#: doSteps of the ClosedLoop rows: its own step (1 ms) and 10 of them (it takes whole multiples).
LOOP_MULTIPLES = (1, 10)


def loop_measurements(program, loops: dict, stop: float, work: Path) -> list:
    """One round of the whole-loop FMUs: [(host, kind, result dict)]."""
    rows = []
    for multiple in LOOP_MULTIPLES:
        each = f", doStep {multiple} ms"
        for kind, fmu in loops.items():
            preload = libpython() if "pythonfmu" in kind else None
            try:
                result = run_c_host_loop(program, fmu, stop, work / f"c_{kind}", preload, multiple)
            except RuntimeError as exc:
                result = {"ok": False, "error": str(exc)[-500:]}
            rows.append(("C host (libcosimc)", kind + each, result))
            rows.append(("fmpy (FMU2Slave)", kind + each, run_child(FMPY_CHILD, fmu, stop, multiple)))
    return rows


def run_child(code: str, *args) -> dict:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    run = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True, env=env,
                         cwd=ROOT, timeout=3600)
    lines = [line for line in run.stdout.splitlines() if line.startswith("{")]
    if run.returncode != 0 or not lines:
        return {"ok": False, "error": (run.stderr.strip() or run.stdout.strip())[-500:]}
    return json.loads(lines[-1])


def package_measurements(program, packages: dict, stop: float, work: Path) -> list:
    """One round: [(host, kind, result dict)] for every package host and package."""
    rows = []
    for kind, package in packages.items():
        preload = libpython() if "pythonfmu" in kind else None      # its FMUs load only so
        try:
            rows.append(("C host (libcosimc)", kind, run_c_host(program, package, stop, work / f"c_{kind}", preload)))
        except RuntimeError as exc:
            rows.append(("C host (libcosimc)", kind, {"ok": False, "error": str(exc)[-500:]}))
        rows.append(("libcosimpy", kind, run_child(LIBCOSIMPY_CHILD, package, stop)))
        rows.append(("ecospy (1 CPU)", kind, run_child(ECOSPY_CHILD, package, stop)))
    return rows


def measurements(program, packages: dict, stop: float, work: Path, python_dir: Path, without=()) -> list:
    """One round: [(host, kind, result dict)] for every host and package, then our master's:
    pythonfmu, native, and native with the models ``without`` left pythonfmu (if any)."""
    rows = package_measurements(program, packages, stop, work)
    rows.append(("our master --mode fmu", "pythonfmu",
                 run_child(MASTER_CHILD, SCENE, "pythonfmu", python_dir, stop, "")))
    if without:
        rows.append(("our master --mode fmu --native", f"native but {', '.join(without)}",
                     run_child(MASTER_CHILD, SCENE, "native", work / "master_native", stop, ",".join(without))))
    rows.append(("our master --mode fmu --native", "native",
                 run_child(MASTER_CHILD, SCENE, "native", work / "master_native", stop, "")))
    return rows


def best_of(rounds: list) -> list:
    """Per (host, kind): the round with the least stepping CPU (the machine is shared)."""
    best = {}
    for rows in rounds:
        for host, kind, r in rows:
            key = (host, kind)
            if key not in best or (r.get("ok") and r.get("cpu_s", 1e99) < best[key].get("cpu_s", 1e99)):
                best[key] = r
    return [(host, kind, r) for (host, kind), r in best.items()]


def table(rows: list, stop: float) -> str:
    lines = ["| host | FMUs | CPU µs per simulated ms | × real time | setup CPU [s] | completed |",
             "|---|---|---|---|---|---|"]
    for host, kind, r in rows:
        if not r.get("ok") or "cpu_s" not in r:
            lines.append(f"| {host} | {kind} | - | - | - | no: {r.get('error', '')[:120]} |")
            continue
        timed = r.get("timed_s", stop)
        per_ms = 1e6 * r["cpu_s"] / (1e3 * timed)
        setup = "-" if r.get("setup_cpu_s") is None else f"{r['setup_cpu_s']:.3f}"
        lines.append(f"| {host} | {kind} | {per_ms:.2f} | {timed / r['cpu_s']:.0f} | {setup} | yes |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--native-dir", default=None,
                        help="the native FMUs (default: parcosim build --native into a temporary folder)")
    parser.add_argument("--python-dir", default=None, help="the pythonfmu FMUs (built there when missing)")
    parser.add_argument("--stop", type=float, default=11.0, help="simulated seconds (default: the scene's 11)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", default=str(RESULTS))
    parser.add_argument("--master-only", action="store_true", help="only our master's rows (no packages, hosts)")
    parser.add_argument("--without", nargs="*", default=[],
                        help="models also left pythonfmu in a --native master row (e.g. DCMotorDrive)")
    parser.add_argument("--loop-only", action="store_true", help="only the whole-loop FMUs (ClosedLoop)")
    parser.add_argument("--per-component", action="store_true",
                        help="only the per-component package (issue 26), pythonfmu and native, in the package hosts")
    args = parser.parse_args(argv)

    from tests.native_host.host import build_host

    work = Path(tempfile.mkdtemp(prefix="native_speed_"))
    python_dir = Path(args.python_dir) if args.python_dir else work / "pythonfmu"
    native_dir = Path(args.native_dir) if args.native_dir else work / "native"
    if args.master_only:
        from fmus.export.build import ensure_built
        from scenarios.scenes import get_scene
        ensure_built(sorted({c.model for c in get_scene(SCENE).system.components}), python_dir)
        packages, loops, program = {}, {}, None
    elif args.per_component:
        packages, loops, program = export_per_component_packages(work, python_dir, SCENE), {}, build_host(work)
    else:
        if not args.native_dir and not args.loop_only:
            from fmus.native.build import build_native_all
            build_native_all(native_dir)
        packages = {} if args.loop_only else export_packages(work, native_dir, python_dir, SCENE)
        loops = export_loops(work, SCENE)
        program = build_host(work)
    load = os.getloadavg()[0]
    rounds = [(loop_measurements(program, loops, args.stop, work) if loops else [])
              + ([] if args.loop_only else package_measurements(program, packages, args.stop, work)
                 if args.per_component else measurements(program, packages, args.stop, work, python_dir, args.without))
              for _ in range(args.rounds)]
    rows = best_of(rounds)
    text = table(rows, args.stop)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    print(f"{SCENE}, {args.stop:g} s simulated, best of {args.rounds} rounds, {stamp}, load {load:.1f}\n\n{text}")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps({"scene": SCENE, "stop_s": args.stop, "rounds": rounds, "date": stamp,
                                          "load": load, "best": rows}, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
