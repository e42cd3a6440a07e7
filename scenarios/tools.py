"""A scene's package run in other people's tools, judged by what a user sees: its tracking.

``python -m scenarios.tools [SCENE ...] [--tools fmpy,ecos,libcosim] [--stop-time S]
[--out FILE.md]`` exports each scene (:func:`scenarios.package.export_package`, the
default of ``parcosim export-ssp``), runs the package in each tool, each run in its own
process, as the tool's documentation says (nothing but the ``.ssp``):

* fmpy: ``fmpy.ssp.simulation.simulate_ssp(path, stop_time, step_size)``, plain (it
  ignores parameter bindings and feeds 0.0 to every input on the first step; its row
  labelled t holds the values at t + h);
* Ecos: ``ecospy.EcosSimulation`` initialised with the parameter set the package
  declares (``"parameters"``), :func:`fmus.ssp_run.simulate_ssp_ecos`;
* libcosim: ``CosimExecution.from_ssp_file(path)``, the step from the package's OSP
  annotation, :func:`fmus.libcosim_runner.simulate_ssp_libcosim`;

and prints, per scene and tool, e_ef and τ_ef (7.31-7.32) against ``parcosim run SCENE``
and the wall time per step.  With no scene: all 16 bench scenes and thesis_sim_circle
(about 4 minutes here).  ``--docs`` puts the table into docs/ssp.md.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import pickle
import subprocess
import sys
import tempfile
import time as _time
from pathlib import Path

import numpy as np

from fmus.ssp_run import SspRun

from .metrics import scene_metrics
from .package import export_package, package_scene
from .run import run_scene
from .scenes import Scene, get_scene, scene_names

TOOLS = ("fmpy", "ecos", "libcosim")
#: The scenes of the table: the thesis' simulation and the 16 bench scenes (the pendulum's
#: scenes have no default package: ``parcosim export-ssp`` refuses them, use --per-component).
TABLE_SCENES = tuple(n for n in scene_names() if not n.startswith(("thesis_sim_circle_me", "pendulum_")))


def short(scene: Scene, stop_time: float | None) -> Scene:
    """``scene`` ending at ``stop_time`` (None: as it is); its metric window ends there too."""
    if stop_time is None or stop_time >= scene.system.stop_time:
        return scene
    start, end = scene.window
    return dataclasses.replace(scene, system=dataclasses.replace(scene.system, stop_time=stop_time),
                               window=(min(start, stop_time / 2), min(end, stop_time)))


def run_tool(tool: str, path, signals, stop_time: float, step: float) -> SspRun:
    """Run the package ``path`` in ``tool`` (one of :data:`TOOLS`) in this process, plainly,
    and return what it recorded with the true time of each row."""
    if tool == "fmpy":
        from fmpy.ssp.simulation import simulate_ssp

        start = _time.perf_counter()
        rows = simulate_ssp(str(path), stop_time=stop_time, step_size=step)
        wall = _time.perf_counter() - start
        # fmpy labels the values after the step from t with t; it may take a step more.
        time = rows["time"] + step
        keep = time <= stop_time + 1e-6 * step
        return SspRun(time=time[keep], signals={s: np.asarray(rows[s])[keep] for s in signals},
                      tool="fmpy", wall_s=wall)
    if tool == "ecos":
        from fmus.ssp_run import simulate_ssp_ecos

        return simulate_ssp_ecos(path, list(signals), stop_time=stop_time, step_size=step)
    if tool == "libcosim":
        from fmus.libcosim_runner import simulate_ssp_libcosim

        return simulate_ssp_libcosim(path, list(signals), stop_time=stop_time, step_size=step)
    raise ValueError(f"tool = {tool!r}; valid: {', '.join(TOOLS)}")


def run_tool_isolated(tool: str, path, signals, stop_time: float, step: float, timeout: float = 3600) -> SspRun:
    """:func:`run_tool` in a child process (a tool that crashes or aborts takes only the
    child with it: then a RuntimeError with the child's last words)."""
    with tempfile.TemporaryDirectory(prefix="parcosim_tool_") as tmp:
        out = Path(tmp) / "run.pickle"
        child = subprocess.run([sys.executable, "-m", "scenarios.tools", "--child", tool, str(path), str(out),
                                repr(stop_time), repr(step), *signals],
                               capture_output=True, text=True, timeout=timeout)
        if child.returncode != 0 or not out.exists():
            tail = (child.stderr or child.stdout).strip().splitlines()[-3:]
            raise RuntimeError(f"{tool} run of {path} ended with status {child.returncode}: {' | '.join(tail)}")
        with open(out, "rb") as f:
            return pickle.load(f)


def tool_metrics(scene: Scene, run: SspRun) -> dict:
    """The scene's metrics (:func:`scenarios.metrics.scene_metrics`) of a tool's run of its
    package, whose signals are named as in :func:`scenarios.package.package_scene`."""
    columns = {"t": run.time}
    packaged = package_scene(scene).scene
    columns.update({name: run[signal] for name, signal in packaged.columns.items() if name in
                    ("x", "y", "x_d", "y_d", "tau1", "tau2")})
    reached = len(run.time) and run.time[-1] >= scene.system.stop_time - 1e-6
    return scene_metrics(scene, columns, run.wall_s, run.error is None and bool(reached))


def compare(scene: Scene, tools=TOOLS, isolated: bool = True, out_dir=None) -> list:
    """Export ``scene``, run it in each tool and in our master; one row per tool:
    (tool, tool's metrics, our metrics, error or None)."""
    ours = run_scene(scene, mode="inprocess").metrics
    signals = ("plant.x", "plant.y", "control.traj.x_d", "control.traj.y_d", "control.ctrl.tau1",
               "control.ctrl.tau2")
    rows = []
    with tempfile.TemporaryDirectory(prefix="parcosim_pkg_") as tmp:
        path = export_package(scene, Path(out_dir or tmp) / f"{scene.name}.ssp")
        for tool in tools:
            runner = run_tool_isolated if isolated else run_tool
            try:
                run = runner(tool, path, signals, scene.system.stop_time, scene.system.step)
            except Exception as exc:  # noqa: BLE001 - a tool's failure is a row of the table
                rows.append((tool, None, ours, f"{type(exc).__name__}: {exc}"))
                continue
            rows.append((tool, tool_metrics(scene, run), ours, run.error))
    return rows


def _ratio(a, b):
    return a / b if (b and math.isfinite(a) and math.isfinite(b)) else float("nan")


def table(results: dict) -> str:
    """Markdown table of ``{scene: compare(...)}``."""
    lines = ["| scene | tool | e_ef [mm] (ours) | e_ef ratio | τ_ef ratio | completed | µs per step |",
             "|---|---|---|---|---|---|---|"]
    for name, rows in results.items():
        for tool, m, ours, error in rows:
            if m is None:
                lines.append(f"| {name} | {tool} | – ({ours['e_ef_mm']:.4g}) | – | – | no: {error} | – |")
                continue
            steps = max(m["simulated_s"] / 1e-3, 1)
            lines.append(f"| {name} | {tool} | {m['e_ef_mm']:.4g} ({ours['e_ef_mm']:.4g}) | "
                         f"{_ratio(m['e_ef_mm'], ours['e_ef_mm']):.4f} | "
                         f"{_ratio(m['tau_ef_Nm'], ours['tau_ef_Nm']):.4f} | "
                         f"{'yes' if m['completed'] else 'no: ' + str(error)} | {1e6 * m['wall_s'] / steps:.0f} |")
    return "\n".join(lines) + "\n"


def _child(argv) -> None:
    tool, path, out, stop, step, *signals = argv
    run = run_tool(tool, path, signals, float(stop), float(step))
    with open(out, "wb") as f:
        pickle.dump(run, f)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--child":
        _child(argv[1:])
        return 0
    parser = argparse.ArgumentParser(prog="python -m scenarios.tools", description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", help=f"scene names (default: the {len(TABLE_SCENES)} of the table)")
    parser.add_argument("--tools", default=",".join(TOOLS), help="comma-separated, from " + ", ".join(TOOLS))
    parser.add_argument("--stop-time", type=float, default=None, help="shorten every scene to this [s]")
    parser.add_argument("--out", default=None, help="also write the markdown table here")
    parser.add_argument("--docs", action="store_true", help="also put the table into docs/ssp.md")
    args = parser.parse_args(argv)
    tools = [t for t in args.tools.split(",") if t]
    results = {}
    for name in args.scenes or TABLE_SCENES:
        scene = short(get_scene(name), args.stop_time)
        start = _time.perf_counter()
        results[name] = compare(scene, tools)
        print(f"{name}: " + ", ".join(
            f"{tool} {_ratio(m['e_ef_mm'], ours['e_ef_mm']):.4f}" if m else f"{tool} failed ({error})"
            for tool, m, ours, error in results[name]) + f" [{_time.perf_counter() - start:.0f} s]",
            file=sys.stderr, flush=True)
    text = table(results)
    print(text)
    if args.out:
        Path(args.out).write_text(text)
    if args.docs:
        write_docs_table(text)
    return 0


#: Where :func:`write_docs_table` puts the table: between these lines of docs/ssp.md.
DOCS = Path(__file__).resolve().parent.parent / "docs" / "ssp.md"
TABLE_START, TABLE_END = "<!-- tools table: python -m scenarios.tools --docs -->", "<!-- end of tools table -->"


def write_docs_table(text: str, path=DOCS) -> None:
    """Replace the table between :data:`TABLE_START` and :data:`TABLE_END` in ``path``."""
    doc = Path(path).read_text()
    start, end = doc.index(TABLE_START) + len(TABLE_START), doc.index(TABLE_END)
    Path(path).write_text(doc[:start] + "\n" + text + doc[end:])


if __name__ == "__main__":
    raise SystemExit(main())
