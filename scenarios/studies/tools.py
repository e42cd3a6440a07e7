"""A scene's packages run in other people's tools, judged by what a user sees: its tracking.

``python -m scenarios.studies.tools [SCENE ...] [--tools fmpy,ecos,libcosim] [--kinds K,...]
[--stop-time S] [--results FILE.json] [--out FILE.md] [--docs]`` exports each scene as each
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
thesis_sim_circle.  Every finished run is stored in ``--results`` (default
``benchmarks/results/tools.json``) as soon as it ends, and a run stored there is not run
again: an interrupted measurement resumes.  ``--docs`` puts the tables of every run stored
there (this call's and earlier ones, e.g. whole default packages and 3 s copies of the
per-component ones) into docs/ssp.md and the summary into the README.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
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

from scenarios.run.metrics import scene_metrics
from scenarios.packaging.chain import export_package, package_scene
from scenarios.run.runner import run_scene
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.scene import Scene

TOOLS = ("fmpy", "ecos", "libcosim")
#: Package kinds: the default two-instance package (scenarios.packaging.chain), the per-component
#: package (scenarios.packaging.per_component) as exported, with both drives swapped for the C drive
#: of the foreign-FMU tests (tests/support/cfmu/dcdrive.c) in the package file, and with
#: the drives' internal observers at the chosen base step and at the plain 1 ms step.
KINDS = ("default", "per-component", "per-component+c-drive", "internal-observer", "internal-observer-1ms")
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
    """``scene`` ending at ``stop_time`` (None: as it is); its metric window ends there too."""
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
    """The C drive FMU of the foreign-FMU tests, compiled into ``out_dir``."""
    sys.path.insert(0, str(C_DRIVE_DIR))
    try:
        from build import build_c_fmu
    finally:
        sys.path.remove(str(C_DRIVE_DIR))
    return build_c_fmu("DCDrive", out_dir)


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


def export_kind(kind: str, scene: Scene, directory, c_drive=None) -> Exported:
    """Export ``scene`` as package ``kind`` (:data:`KINDS`) into ``directory``."""
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
        path = export_per_component(scene, path, substeps=1 if kind.endswith("1ms") else None,
                                    internal_observer=True)
    else:
        path = export_per_component(scene, path)
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
    recorded with the true time of each row."""
    if tool == "fmpy":
        start = _time.perf_counter()
        if bindings:
            from fmus.ssp.run import simulate_ssp_fmpy

            run = simulate_ssp_fmpy(path, stop_time, step, initial_outputs=False)
            time, rows = run.time, run.signals
        else:
            from fmpy.ssp.simulation import simulate_ssp

            rows = simulate_ssp(str(path), stop_time=stop_time, step_size=step)
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
            c_drive=None, ours: dict | None = None) -> list:
    """Export ``scene`` as ``kind``, run it in each tool and (unless ``ours`` is given) in
    our master; one row per tool: (tool, tool's metrics, our metrics, error or None).
    The tool's metrics carry ``cpu_s`` when ``isolated``."""
    ours = run_scene(scene, mode="inprocess").metrics if ours is None else ours
    rows = []
    with tempfile.TemporaryDirectory(prefix="parcosim_pkg_") as tmp:
        exported = export_kind(kind, scene, out_dir or tmp, c_drive)
        for tool in tools:
            runner = run_tool_isolated if isolated else run_tool
            try:
                run = runner(tool, exported.path, list(exported.columns), scene.system.stop_time, exported.step,
                             bindings=exported.foreign and tool == "fmpy")
            except Exception as exc:  # noqa: BLE001 - a tool's failure is a row of the table
                rows.append((tool, None, ours, f"{type(exc).__name__}: {exc}"))
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


def summary(results: dict) -> str:
    """One line per package kind and tool: the ranges of the ratios over the scenes, runs
    completed, the median CPU µs per simulated ms."""
    groups = {}
    for key, rows in results.items():
        kind = key[0] if isinstance(key, tuple) else "default"
        for tool, m, ours, _ in rows:
            groups.setdefault((kind, tool), []).append((m, ours))
    lines = ["| package | tool | e_ef / ours | τ_ef / ours | runs completed | simulated [s] | "
             "CPU µs per simulated ms (median) |", "|---|---|---|---|---|---|---|"]
    for (kind, tool), items in groups.items():
        done = [(m, o) for m, o in items if m is not None and m["completed"]]
        e = [_ratio(m["e_ef_mm"], o["e_ef_mm"]) for m, o in done]
        t = [_ratio(m["tau_ef_Nm"], o["tau_ef_Nm"]) for m, o in done]
        cpu = [_cpu_per_ms(m) for m, _ in done if math.isfinite(_cpu_per_ms(m))]
        span = (lambda v: f"{min(v):.4f}-{max(v):.4f}" if v else "–")
        lengths = sorted({round(m["simulated_s"], 3) for m, _ in done})
        length = "–" if not lengths else (f"{lengths[0]:g}" if len(lengths) == 1 else
                                          f"{lengths[0]:g}-{lengths[-1]:g}")
        lines.append(f"| {kind} | {tool} | {span(e)} | {span(t)} | {len(done)}/{len(items)} | {length} | "
                     f"{f'{np.median(cpu):.0f}' if cpu else '–'} |")
    return "\n".join(lines) + "\n"


# --- the resumable measurement ---------------------------------------------------------------

def _key(kind, scene, tool, stop_time) -> str:
    return f"{kind}|{scene}|{tool}|{stop_time if stop_time is not None else 'full'}"


def load_results(path=RESULTS) -> dict:
    """The runs stored so far (key "kind|scene|tool|stop" -> row), {} without a file."""
    path = Path(path)
    return json.loads(path.read_text()) if path.exists() else {}


def _store(path, stored: dict) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(stored, indent=1, sort_keys=True, default=float))
    tmp.replace(path)


def measure(scenes, tools, kinds, stop_time=None, results=RESULTS, progress=print) -> dict:
    """Run what ``results`` does not hold yet, storing each run as it ends; return
    ``{(kind, scene): rows}`` of everything asked for (from the file or new)."""
    stored = load_results(results)
    table_rows = {}
    c_drive = None
    with tempfile.TemporaryDirectory(prefix="parcosim_tools_") as tmp:
        for name in scenes:
            full = get_scene(name)
            scene = short(full, stop_time)
            stop = stop_time if scene is not full else None    # a scene shorter than stop_time runs whole
            ours_key = _key("ours", name, "parcosim", stop)
            for kind in kinds:
                if kind.startswith("internal-observer") or kind.endswith("c-drive"):
                    if not {"drive1", "drive2"} <= {c.name for c in scene.system.components}:
                        continue
                todo = [t for t in tools if _key(kind, name, t, stop) not in stored]
                if todo:
                    if ours_key not in stored:
                        stored[ours_key] = run_scene(scene, mode="inprocess").metrics
                        _store(results, stored)
                    if kind.endswith("c-drive") and c_drive is None:
                        c_drive = build_c_drive(Path(tmp) / "c")
                    start = _time.perf_counter()
                    for tool, m, _, error in compare(scene, todo, kind=kind, c_drive=c_drive,
                                                     ours=stored[ours_key]):
                        stored[_key(kind, name, tool, stop)] = {"metrics": m, "error": error}
                        _store(results, stored)
                        progress(f"{kind} {name} {tool}: " + (f"e_ef x{_ratio(m['e_ef_mm'], stored[ours_key]['e_ef_mm']):.4f}"
                                 if m else f"failed ({error})") + f" [{_time.perf_counter() - start:.0f} s]")
                table_rows[(kind, name)] = [
                    (t, stored[_key(kind, name, t, stop)]["metrics"], stored[ours_key],
                     stored[_key(kind, name, t, stop)]["error"]) for t in tools]
    return table_rows


def stored_rows(stored: dict, tools=TOOLS) -> dict:
    """Every run in ``stored`` (:func:`load_results`) as ``{(kind, scene): rows}``, in the
    order of :data:`KINDS` and :data:`TABLE_SCENES`; runs of copies shortened to ``stop`` s
    under the kind ``"<kind>, <stop> s copies"``."""
    found = {}
    for key, value in stored.items():
        kind, scene, tool, stop = key.split("|")
        if kind == "ours" or tool not in tools:
            continue
        ours = stored.get(_key("ours", scene, "parcosim", None if stop == "full" else float(stop)))
        if ours is None:
            continue
        found.setdefault((kind, stop, scene), []).append((tool, value["metrics"], ours, value["error"]))

    def order(item):
        (kind, stop, scene), _ = item
        rank = TABLE_SCENES.index(scene) if scene in TABLE_SCENES else len(TABLE_SCENES)
        return (KINDS.index(kind) if kind in KINDS else len(KINDS), stop != "full", stop, rank)

    return {(kind if stop == "full" else f"{kind}, {float(stop):g} s copies", scene):
            sorted(rows, key=lambda r: tools.index(r[0])) for (kind, stop, scene), rows in sorted(found.items(), key=order)}


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
    parser.add_argument("--stop-time", type=float, default=None, help="shorten every scene to this [s]")
    parser.add_argument("--results", default=str(RESULTS), help="the runs stored so far (resumes from it)")
    parser.add_argument("--out", default=None, help="also write the markdown tables here")
    parser.add_argument("--docs", action="store_true",
                        help="put the tables of every stored run into docs/ssp.md, the summary into the README")
    args = parser.parse_args(argv)
    tools = [t for t in args.tools.split(",") if t]
    kinds = [k for k in args.kinds.split(",") if k]
    for k in kinds:
        if k not in KINDS:
            parser.error(f"--kinds {k}: one of {', '.join(KINDS)}")
    results = measure(args.scenes or TABLE_SCENES, tools, kinds, args.stop_time, args.results,
                      progress=lambda line: print(line, file=sys.stderr, flush=True))
    if args.docs:   # the tables hold every stored run, this call's and earlier ones
        results = stored_rows(load_results(args.results), tools)
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
