"""A scene's packages run in other people's tools, judged by what a user sees: its tracking.

``python -m scenarios.tools [SCENE ...] [--tools fmpy,ecos,libcosim] [--kinds K,...]
[--results FILE.json] [--out FILE.md] [--docs]`` exports each whole scene as each
package kind (:data:`KINDS`), runs the package in each tool, each run in its own process,
as the tool's documentation says (nothing but the ``.ssp`` and its step):

* fmpy: ``fmpy.ssp.simulation.simulate_ssp(path, stop_time, step_size)``, plain (it
  ignores parameter bindings and feeds 0.0 to every input on the first step; its row
  labelled t holds the values at t + h); with a foreign FMU in the package, whose start
  values are not the slot's, fmpy's runner with the package's bindings as its
  ``parameter_set`` (:func:`fmus.ssp.run.simulate_ssp_fmpy`, ``initial_outputs=False``);
* Ecos: ``ecospy.EcosSimulation(step, ssp_path)`` initialised with the parameter set the
  package declares (``"parameters"``), :func:`fmus.ssp.run.simulate_ssp_ecos`;
* libcosim: ``CosimExecution.from_ssp_file(path)``, the step from the package's OSP
  annotation, :func:`fmus.ssp.libcosim.simulate_ssp_libcosim`;

and reports, per kind, scene and tool, e_ef and τ_ef (7.31-7.32, at the period's
communication points) against ``parcosim run SCENE`` and the CPU time the tool's process
spent per simulated ms, from its start (Python, imports, loading, initialisation included:
what a fresh importing process pays).  With no scene: all 16 bench scenes and
thesis_sim_circle.  Every finished run is merged into ``--results`` (default
``benchmarks/results/tools.json``) as soon as it ends, stamped with the commit measured
and the load average, and a run stored there is not run again: an interrupted measurement
resumes.  ``--docs`` runs nothing: it puts the tables of every run stored there into
docs/ssp.md and the summary into the README; nothing else writes the docs.
"""
from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import json
import math
import os
import pickle
import resource
import subprocess
import sys
import tempfile
import time as _time
import zipfile
from pathlib import Path

import numpy as np

from controller.strategies import STRATEGY_NAMES
from fmus.ssp.run import SspRun
from fmus.status import RunError, RunStatus

from scenarios.run.metrics import scene_metrics
from scenarios.packaging.chain import export_package, package_scene
from scenarios.run.runner import run_scene
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.scene import Scene

TOOLS = ("fmpy", "ecos", "libcosim")
#: Package kinds: the default two-instance package (scenarios.packaging.chain), the per-component
#: package (scenarios.packaging.per_component) as exported, with both drives swapped for the C drive
#: of the foreign-FMU tests (tests/support/cfmu/dcdrive.c) in the package file, and with
#: the drives' internal observers at the chosen base step and at the plain 1 ms step, and the
#: per-component package of native FMUs (``--native``: same instances, base step and phases).
KINDS = ("default", "per-component", "per-component+c-drive", "internal-observer", "internal-observer-1ms",
         "per-component-native")
#: The scenes of the table: the thesis' simulation and the 16 bench scenes of the thesis'
#: strategies (any other scene of ``scene_names()`` runs when named).
TABLE_SCENES = ("thesis_sim_circle",) + tuple(f"bench_{kind}_{s}" for kind in ("circle", "triangle")
                                              for s in STRATEGY_NAMES)
#: The scene's columns the metrics read (what each run records).
METRIC_COLUMNS = ("x", "y", "x_d", "y_d", "tau1", "tau2")
ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results" / "tools.json"
#: The swapped-in drive's source (the foreign-FMU tests build it the same way).
C_DRIVE_DIR = ROOT / "tests" / "support" / "cfmu"


def short(scene: Scene, stop_time: float | None) -> Scene:
    """``scene`` ending at ``stop_time`` (None: as it is); its metric window ends there too
    (for the tests' short runs: the measurement runs whole scenes)."""
    if stop_time is None or stop_time >= scene.system.stop_time:
        return scene
    start, end = scene.window
    return dataclasses.replace(scene, system=dataclasses.replace(scene.system, stop_time=stop_time),
                               window=(min(start, stop_time / 2), min(end, stop_time)))


@dataclasses.dataclass(frozen=True)
class Exported:
    """A package to run: its file, its step, the scene's columns by package signal, and
    whether a foreign FMU in it needs the bindings in fmpy."""

    path: Path
    step: float
    columns: dict
    foreign: bool = False


def build_c_drive(out_dir) -> Path:
    """The C drive FMU of the foreign-FMU tests, compiled into ``out_dir``.  Its build script is loaded by
    its path: a module named ``build`` imported before (PyPA's build, a user's) is not taken for it."""
    spec = importlib.util.spec_from_file_location("parcosim_cfmu_build", C_DRIVE_DIR / "build.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    return script.build_c_fmu("DCDrive", out_dir)


def swap_fmus(package, replacements: dict, out) -> Path:
    """Copy the package with ``resources/<instance>.fmu`` replaced by the given FMU files,
    as a user does with any zip tool (nothing else changes: the SSD, its bindings)."""
    members = {f"resources/{instance}.fmu": Path(fmu).read_bytes() for instance, fmu in replacements.items()}
    with zipfile.ZipFile(package) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        missing = set(members) - set(src.namelist())
        if missing:
            raise ValueError(f"{package} has no {', '.join(sorted(missing))}")
        for item in src.infolist():
            data = members.get(item.filename)
            dst.writestr(item, src.read(item) if data is None else data)
    return Path(out)


def export_kind(kind: str, scene: Scene, directory, c_drive=None, substeps: int | None = None) -> Exported:
    """Export ``scene`` as package ``kind`` (:data:`KINDS`) into ``directory`` (``substeps``:
    the per-component kinds' n, None: chosen by the export's trial; the ``-1ms`` kind: 1)."""
    from scenarios.packaging.per_component import export_per_component

    path = Path(directory) / f"{scene.name}.{kind}.ssp"
    if kind == "default":
        packaged = package_scene(scene).scene
        return Exported(export_package(scene, path), scene.system.step,
                        {signal: name for name, signal in packaged.columns.items() if name in METRIC_COLUMNS})
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r}; valid: {', '.join(KINDS)}")
    columns = {signal: name for name, signal in scene.columns.items() if name in METRIC_COLUMNS}
    if kind.startswith("internal-observer"):
        path = export_per_component(scene, path, substeps=1 if kind.endswith("1ms") else substeps,
                                    internal_observer=True)
    else:
        path = export_per_component(scene, path, substeps=substeps, native=kind == "per-component-native")
    from fmus.ssp.export import read_ssp_experiment

    step = read_ssp_experiment(path)[2]
    if kind != "per-component+c-drive":
        return Exported(path, step, columns)
    drives = [c.name for c in scene.system.components if c.name in ("drive1", "drive2")]
    if not drives:
        raise ValueError(f"scene {scene.name} has no drive1/drive2 to swap")
    swapped = swap_fmus(path, {d: c_drive for d in drives}, path.with_suffix(".swapped.ssp"))
    return Exported(swapped, step, columns, foreign=True)


def run_tool(tool: str, path, signals, stop_time: float, step: float, bindings: bool = False) -> SspRun:
    """Run the package ``path`` in ``tool`` (one of :data:`TOOLS`) in this process, plainly
    (fmpy with ``bindings``: its runner given the package's bindings), and return what it
    recorded with the true time of each row, or, for a run a component stopped, ``error``
    (the record :func:`fmus.ssp.run.tool_refusal` makes; fmpy's rows are lost then)."""
    if tool == "fmpy":
        from fmpy.fmi1 import FMICallException

        from fmus.ssp.run import fmpy_watch, simulate_ssp_fmpy

        start = _time.perf_counter()
        if bindings:
            run = simulate_ssp_fmpy(path, stop_time, step, initial_outputs=False)
            time, rows = run.time, run.signals
            if run.error is not None:
                return run
        else:
            from fmpy.ssp.simulation import simulate_ssp

            with fmpy_watch() as watch:    # only to know who refused: the run is fmpy's own
                try:
                    rows = simulate_ssp(str(path), stop_time=stop_time, step_size=step)
                except FMICallException as exc:
                    return SspRun(time=np.empty(0), signals={s: np.empty(0) for s in signals}, tool="fmpy",
                                  wall_s=_time.perf_counter() - start, error=watch.refusal(exc))
            time = rows["time"] + step   # fmpy labels the values after the step from t with t
        wall = _time.perf_counter() - start
        keep = time <= stop_time + 1e-6 * step   # it may take a step more
        return SspRun(time=time[keep], signals={s: np.asarray(rows[s])[keep] for s in signals},
                      tool="fmpy", wall_s=wall)
    if tool == "ecos":
        from fmus.ssp.run import simulate_ssp_ecos

        return simulate_ssp_ecos(path, list(signals), stop_time=stop_time, step_size=step)
    if tool == "libcosim":
        from fmus.ssp.libcosim import simulate_ssp_libcosim

        return simulate_ssp_libcosim(path, list(signals), stop_time=stop_time, step_size=step)
    raise ValueError(f"tool = {tool!r}; valid: {', '.join(TOOLS)}")


def run_tool_isolated(tool: str, path, signals, stop_time: float, step: float, bindings: bool = False,
                      timeout: float = 3600) -> SspRun:
    """:func:`run_tool` in a child process (a tool that crashes or aborts takes only the
    child with it: then a RuntimeError with the child's last words).  ``extra["cpu_s"]``:
    the child's CPU time from its start to its end (user + system)."""
    with tempfile.TemporaryDirectory(prefix="parcosim_tool_") as tmp:
        out = Path(tmp) / "run.pickle"
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        child = subprocess.run([sys.executable, "-m", "scenarios.studies.tools", "--child", tool, str(path), str(out),
                                repr(stop_time), repr(step), str(int(bindings)), *signals],
                               capture_output=True, text=True, timeout=timeout, cwd=ROOT)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if child.returncode != 0 or not out.exists():
            tail = (child.stderr or child.stdout).strip().splitlines()[-3:]
            raise RuntimeError(f"{tool} run of {path} ended with status {child.returncode}: {' | '.join(tail)}")
        with open(out, "rb") as f:
            run = pickle.load(f)
    run.extra["cpu_s"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return run


def tool_metrics(scene: Scene, run: SspRun, columns: dict, period: float | None = None) -> dict:
    """The scene's metrics (:func:`scenarios.run.metrics.scene_metrics`) of a tool's run of a
    package, at the communication points of the scene's period (the rows ``parcosim run``
    has); ``columns``: package signal -> the scene's column name."""
    period = scene.system.step if period is None else period
    k = np.round(run.time / period)
    at = np.abs(run.time - k * period) <= 1e-6 * period
    data = {"t": run.time[at]}
    data.update({name: np.asarray(run[signal])[at] for signal, name in columns.items() if name in METRIC_COLUMNS})
    reached = len(run.time) and run.time[-1] >= scene.system.stop_time - 1e-6
    return scene_metrics(scene, data, run.wall_s, run.error is None and bool(reached))


def compare(scene: Scene, tools=TOOLS, isolated: bool = True, out_dir=None, kind: str = "default",
            c_drive=None, ours: dict | None = None, substeps: int | None = None) -> list:
    """Export ``scene`` as ``kind`` (:func:`export_kind`), run it in each tool and (unless
    ``ours`` is given) in our master; one row per tool: (tool, tool's metrics, our metrics,
    :class:`fmus.status.RunError` or None: the run's ``error``, or a tool that could not run
    at all, kind ``failed``).  The tool's metrics carry ``cpu_s`` when ``isolated``."""
    ours = run_scene(scene, mode="inprocess").metrics if ours is None else ours
    rows = []
    with tempfile.TemporaryDirectory(prefix="parcosim_pkg_") as tmp:
        exported = export_kind(kind, scene, out_dir or tmp, c_drive, substeps)
        for tool in tools:
            runner = run_tool_isolated if isolated else run_tool
            try:
                run = runner(tool, exported.path, list(exported.columns), scene.system.stop_time, exported.step,
                             bindings=exported.foreign and tool == "fmpy")
            except Exception as exc:  # noqa: BLE001 - a tool's failure is a row of the table
                rows.append((tool, None, ours, RunError(RunStatus.FAILED, f"{type(exc).__name__}: {exc}")))
                continue
            m = tool_metrics(scene, run, exported.columns)
            m["cpu_s"] = run.extra.get("cpu_s", float("nan"))
            m["step"] = exported.step
            rows.append((tool, m, ours, run.error))
    return rows


def _ratio(a, b):
    return a / b if (b and a is not None and b is not None and math.isfinite(a) and math.isfinite(b)) else float("nan")


def _cpu_per_ms(m: dict) -> float:
    """CPU µs the tool's process spent per simulated ms (NaN when not measured)."""
    return 1e3 * m.get("cpu_s", float("nan")) / max(1e3 * m["simulated_s"], 1.0) * 1e3


def _cpu_text(m: dict) -> str:
    value = _cpu_per_ms(m)
    return f"{value:.0f}" if math.isfinite(value) else "–"


def table(results: dict) -> str:
    """Markdown table of ``{(kind, scene[, stop]): compare(...)}`` (or ``{scene: ...}``: kind default)."""
    lines = ["| package | scene | tool | step [ms] | e_ef [mm] (ours) | e_ef ratio | τ_ef ratio | completed | "
             "CPU µs per simulated ms |", "|---|---|---|---|---|---|---|---|---|"]
    for key, rows in results.items():
        kind, name = key[:2] if isinstance(key, tuple) else ("default", key)
        for tool, m, ours, error in rows:
            if m is None:
                lines.append(f"| {kind} | {name} | {tool} | – | – ({ours['e_ef_mm']:.4g}) | – | – | no: {error} | – |")
                continue
            lines.append(f"| {kind} | {name} | {tool} | {1e3 * m.get('step', 1e-3):g} | "
                         f"{m['e_ef_mm']:.4g} ({ours['e_ef_mm']:.4g}) | "
                         f"{_ratio(m['e_ef_mm'], ours['e_ef_mm']):.4f} | "
                         f"{_ratio(m['tau_ef_Nm'], ours['tau_ef_Nm']):.4f} | "
                         f"{'yes' if m['completed'] else 'no: ' + str(error)} | {_cpu_text(m)} |")
    return "\n".join(lines) + "\n"


def _span(values, digits: int = 4) -> str:
    return f"{min(values):.{digits}f}-{max(values):.{digits}f}" if values else "–"


def summary(results: dict) -> str:
    """One line per package kind and tool: the ranges over the scenes of the ratios, of the
    step and of the CPU µs per simulated ms (and its median), runs completed."""
    groups = {}
    for key, rows in results.items():
        kind = key[0] if isinstance(key, tuple) else "default"
        for tool, m, ours, _ in rows:
            groups.setdefault((kind, tool), []).append((m, ours))
    lines = ["| package | tool | e_ef / ours | τ_ef / ours | runs completed | step [ms] | simulated [s] | "
             "CPU µs per simulated ms: range (median) |", "|---|---|---|---|---|---|---|---|"]
    for (kind, tool), items in groups.items():
        done = [(m, o) for m, o in items if m is not None and m["completed"]]
        e = [_ratio(m["e_ef_mm"], o["e_ef_mm"]) for m, o in done]
        t = [_ratio(m["tau_ef_Nm"], o["tau_ef_Nm"]) for m, o in done]
        cpu = [_cpu_per_ms(m) for m, _ in done if math.isfinite(_cpu_per_ms(m))]
        steps = sorted({1e3 * m.get("step", 1e-3) for m, _ in done})
        lengths = sorted({round(m["simulated_s"], 3) for m, _ in done})
        span = (lambda v: "–" if not v else (f"{v[0]:g}" if len(v) == 1 else f"{v[0]:g}-{v[-1]:g}"))
        lines.append(f"| {kind} | {tool} | {_span(e)} | {_span(t)} | {len(done)}/{len(items)} | {span(steps)} | "
                     f"{span(lengths)} | {_span(cpu, 0) + f' ({np.median(cpu):.0f})' if cpu else '–'} |")
    return "\n".join(lines) + "\n"


# --- the resumable measurement ---------------------------------------------------------------

def _key(kind, scene, tool) -> str:
    return f"{kind}|{scene}|{tool}"


def load_results(path=RESULTS) -> dict:
    """The runs stored so far (key "kind|scene|tool" -> row; our master's: "ours|scene|parcosim";
    the export's trial: "trial|scene|per-component"), {} without a file."""
    path = Path(path)
    return json.loads(path.read_text()) if path.exists() else {}


def _commit() -> str:
    """The commit measured (with ``+`` when the work tree differs from it)."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=ROOT, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                               text=True, cwd=ROOT, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+" if dirty else "")


def _store(path, key: str, value: dict) -> dict:
    """Merge one run into the file ``path`` (read again, so that runs stored meanwhile by
    another call stay) and return what it holds now."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    stored = load_results(path)
    stored[key] = {**value, "commit": _commit(), "load": round(os.getloadavg()[0], 2)}
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps(stored, indent=1, sort_keys=True, default=float))
    tmp.replace(path)
    return stored


def _stored_error(value: dict) -> RunError | None:
    """The error of a stored run (its record as :meth:`fmus.status.RunError.record` wrote it)."""
    return RunError.from_record(value["error"]) if value.get("error") else None


def _has_drives(scene: Scene) -> bool:
    return {"drive1", "drive2"} <= {c.name for c in scene.system.components}


def _trial(scene: Scene, kind: str, results, stored: dict) -> tuple:
    """(the per-component kind's n, the results held): the export's trial
    (:func:`scenarios.per_component.trial`) run once per scene and observer placement and
    stored (key "trial|scene|per-component" or "...|internal-observer"); (None, stored) for
    the kinds without a trial."""
    from scenarios.packaging.per_component import trial

    if kind == "default" or kind.endswith("1ms"):
        return None, stored
    family = "internal-observer" if kind.startswith("internal-observer") else "per-component"
    key = _key("trial", scene.name, family)
    if key not in stored:
        n, tried, floor = trial(scene, internal_observer=family == "internal-observer")
        stored = _store(results, key, {"substeps": n, "floor": floor,
                                       "tried": {str(k): list(v) for k, v in tried.items()}})
    return stored[key]["substeps"], stored


def measure(scenes, tools, kinds, results=RESULTS, progress=print) -> dict:
    """Run, on the whole scenes, what ``results`` does not hold yet, merging each run into it
    as it ends; return ``{(kind, scene): rows}`` of everything asked for (from the file or new).
    Kinds that swap or fold the drives skip a scene without ``drive1``/``drive2``."""
    stored = load_results(results)
    table_rows = {}
    c_drive = None
    with tempfile.TemporaryDirectory(prefix="parcosim_tools_") as tmp:
        for kind in kinds:
            for name in scenes:
                scene = get_scene(name)
                if (kind.startswith("internal-observer") or kind.endswith("c-drive")) and not _has_drives(scene):
                    continue
                ours_key = _key("ours", name, "parcosim")
                todo = [t for t in tools if _key(kind, name, t) not in stored]
                if todo:
                    if ours_key not in stored:
                        stored = _store(results, ours_key, run_scene(scene, mode="inprocess").metrics)
                    if kind.endswith("c-drive") and c_drive is None:
                        c_drive = build_c_drive(Path(tmp) / "c")
                    substeps, stored = _trial(scene, kind, results, stored)
                    start = _time.perf_counter()
                    for tool, m, _, error in compare(scene, todo, kind=kind, c_drive=c_drive,
                                                     ours=stored[ours_key], substeps=substeps):
                        stored = _store(results, _key(kind, name, tool),
                                        {"metrics": m, "error": error.record() if error else None})
                        progress(f"{kind} {name} {tool}: " + (f"e_ef x{_ratio(m['e_ef_mm'], stored[ours_key]['e_ef_mm']):.4f}"
                                 if m else f"failed ({error})") + f" [{_time.perf_counter() - start:.0f} s]")
                table_rows[(kind, name)] = [
                    (t, stored[_key(kind, name, t)]["metrics"], stored[ours_key],
                     _stored_error(stored[_key(kind, name, t)])) for t in tools]
    return table_rows


def stored_rows(stored: dict, tools=TOOLS) -> dict:
    """Every run in ``stored`` (:func:`load_results`) as ``{(kind, scene): rows}``, in the
    order of :data:`KINDS` and :data:`TABLE_SCENES`."""
    found = {}
    for key, value in stored.items():
        kind, scene, tool = key.split("|")
        ours = stored.get(_key("ours", scene, "parcosim"))
        if kind in ("ours", "trial") or tool not in tools or ours is None:
            continue
        found.setdefault((kind, scene), []).append((tool, value["metrics"], ours, _stored_error(value)))

    def order(item):
        (kind, scene), _ = item
        rank = TABLE_SCENES.index(scene) if scene in TABLE_SCENES else len(TABLE_SCENES)
        return (KINDS.index(kind) if kind in KINDS else len(KINDS), rank)

    return {key: sorted(rows, key=lambda r: tools.index(r[0])) for key, rows in sorted(found.items(), key=order)}


def _child(argv) -> None:
    tool, path, out, stop, step, bindings, *signals = argv
    run = run_tool(tool, path, signals, float(stop), float(step), bindings=bindings == "1")
    with open(out, "wb") as f:
        pickle.dump(run, f)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--child":
        _child(argv[1:])
        return 0
    parser = argparse.ArgumentParser(prog="python -m scenarios.studies.tools", description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", help=f"scene names (default: the {len(TABLE_SCENES)} of the table)")
    parser.add_argument("--tools", default=",".join(TOOLS), help="comma-separated, from " + ", ".join(TOOLS))
    parser.add_argument("--kinds", default=",".join(KINDS), help="comma-separated, from " + ", ".join(KINDS))
    parser.add_argument("--results", default=str(RESULTS), help="the runs stored so far (resumes from it)")
    parser.add_argument("--out", default=None, help="also write the markdown tables here")
    parser.add_argument("--docs", action="store_true",
                        help="run nothing; put the tables of every stored run into docs/ssp.md, the summary "
                             "into the README")
    args = parser.parse_args(argv)
    tools = [t for t in args.tools.split(",") if t]
    kinds = [k for k in args.kinds.split(",") if k]
    for k in kinds:
        if k not in KINDS:
            parser.error(f"--kinds {k}: one of {', '.join(KINDS)}")
    if args.docs:   # only writes: the tables of every stored run, nothing is run
        results = stored_rows(load_results(args.results), tools)
    else:
        results = measure(args.scenes or TABLE_SCENES, tools, kinds, args.results,
                          progress=lambda line: print(line, file=sys.stderr, flush=True))
    text = summary(results) + "\n" + table(results)
    print(text)
    if args.out:
        Path(args.out).write_text(text)
    if args.docs:
        write_docs_table(text)
        write_docs_table(summary(results), README)
    return 0


#: Where :func:`write_docs_table` puts the tables: between these lines of docs/ssp.md (all
#: rows) and of the README (the summary).
DOCS = ROOT / "docs" / "ssp.md"
README = ROOT / "README.md"
TABLE_START, TABLE_END = "<!-- tools table: python -m scenarios.studies.tools --docs -->", "<!-- end of tools table -->"


def write_docs_table(text: str, path=DOCS) -> None:
    """Replace the table between :data:`TABLE_START` and :data:`TABLE_END` in ``path``."""
    doc = Path(path).read_text()
    start, end = doc.index(TABLE_START) + len(TABLE_START), doc.index(TABLE_END)
    Path(path).write_text(doc[:start] + "\n" + text + doc[end:])


if __name__ == "__main__":
    raise SystemExit(main())
