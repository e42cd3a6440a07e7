"""The ``parcosim`` command.

Every subcommand is a thin shell over a documented Python call:

=====================  ==============================================
``parcosim``           ``parcosim run bench_circle_TCMDx`` (the default job)
``parcosim demo``      ``scenarios.examples.plant_demo.run(out_dir, preset)``: the plant alone, a table and a PNG
``parcosim build``     ``fmus.export.build.build_all(out_dir)``; with ``--native``
                       ``fmus.native.build.build_native_all(out_dir, fmi_version)`` (docs/native.md)
``parcosim sweep``     ``scenarios.batch.sweep.run_sweep(scene, samples, uncertainty, seed, distribution,
                       perturb, mode, out_dir, scheduler, workers)``
``parcosim identify-motor``  ``motor.cli.identify_main(argv)``
``parcosim list``      ``scenarios.scenes.catalogue.scene_names()``
``parcosim run``       ``scenarios.run.runner.run_scene(name, mode, out_dir)`` (mode inprocess, fmu or
                       compiled); with ``--native`` (``--mode fmu``)
                       ``run_scene(fmus.native.run.with_native_fmus(scene, fmu_dir), "fmu", ...)``; with ``--drives-in-plant N``
                       ``run_scene(drives_in_plant(get_scene(name), substeps=N), ...)``; with
                       ``--replace I=F.fmu`` ``run_scene(with_fmu_files(scene, {I: F}), ...)``
``parcosim report``    ``scenarios.batch.report.write_report(out_dir, mode)``
``parcosim trade``     ``scenarios.studies.trade.run_trade(scene, quick, out_dir)``; for a pendulum scene
                       ``scenarios.studies.pendulum_trade.run_pendulum_trade(scene, quick, out_dir)``
``parcosim export-ssp``  ``scenarios.packaging.chain.export_package(get_scene(name), path, fmu_dir)``;
                       with ``--per-component [--substeps N] [--internal-observer] [--native]``
                       ``scenarios.packaging.per_component.export_per_component(get_scene(name), path, fmu_dir,
                       substeps, internal_observer, native=native)``
``parcosim export-fmu``  ``fmus.systemfmu.export.export_fmu(get_scene(name).system, path)``; with ``--native``
                       ``fmus.native.loopbuild.export_native_fmu(get_scene(name).system, path, fmi_version=...)`` (docs/native.md)
``parcosim build-plant``  ``fmus.export.specfmu.build_plant_fmu(spec, path)`` (docs/spec.md)
``parcosim workspace``  ``scenarios.studies.workspace.plot_workspace(preset_or_spec, out_dir)`` (docs/workspace.md)
=====================  ==============================================

Errors end the command with exit status 2 and one readable line on stderr, nothing else
printed and nothing left behind (folders the command made are removed while empty): bad
arguments (a misspelled command or scene gets a suggestion), an output that cannot be written
(checked before any work), a file that cannot be written (named).  A run that a component
stops early writes what it recorded, prints the component's message and exits 1; so does a
sweep whose every sample failed (one with some failures exits 0 and says how many).  SIGINT
(Ctrl-C) during ``parcosim run`` writes the whole rows recorded so far and metrics with
``"completed": false``, prints one line and exits 130.  The exit status of each outcome is
one table, :data:`fmus.status.EXIT_STATUS` (docs/contract.md, "Outcomes and errors as data").
"""
from __future__ import annotations

import argparse
import contextlib
import io
import math
import sys
import warnings
import zipfile
from pathlib import Path

from fmus.status import EXIT_STATUS, RunStatus

from .checks import (CommandError, Parser, at_least, check_output, first_missing, non_negative, remove_if_empty,
                     suggestion)


#: Exit status after SIGINT (128 + 2, as shells report it).
EXIT_INTERRUPTED = EXIT_STATUS[RunStatus.INTERRUPTED]
#: Exit status of a refused command (bad arguments, an output that cannot be written).
EXIT_REFUSED = EXIT_STATUS[RunStatus.INVALID]
#: The default job: bare ``parcosim`` is ``parcosim run DEFAULT_SCENE``.
DEFAULT_SCENE = "bench_circle_TCMDx"


def _fmi_version_option(command, text: str = "with --native: FMI 2.0 (default) or FMI 3.0 co-simulation FMUs, the "
                                                  "same C under either (docs/native.md)") -> None:
    command.add_argument("--fmi-version", type=int, choices=(2, 3), default=2, help=text)


#: Why ``run --mode fmu --native --fmi-version 3`` is refused: the master's FMU back end
#: (``fmus.cosim.backends._FmuInstance``: fmpy's FMU2Slave, the fmi2 set/get/doStep/state calls of
#: the step path) is FMI 2.0 throughout; FMI 3.0 changes every one of those calls, so it
#: would be a second back end, to run the same C as the FMI 2.0 FMUs (docs/native.md "FMI 3.0").
FMI3_RUN_REFUSED = ("--fmi-version 3: parcosim run --mode fmu --native runs FMI 2.0 FMUs only (the master's FMU "
                    "back end is FMI 2.0); the FMI 3.0 native FMUs, the same C, are for FMI 3.0 importers: "
                    "parcosim build --native --fmi-version 3, parcosim export-fmu SCENE OUT.fmu --native "
                    "--fmi-version 3")


def _parser() -> argparse.ArgumentParser:
    parser = Parser(prog="parcosim", description=f"Co-simulate the 5R robot's and the wheeled pendulum's scenes, "
                     f"export them as FMUs and SSP packages. Bare `parcosim` runs `parcosim run {DEFAULT_SCENE}` "
                     f"(the bench circle; files in out/{DEFAULT_SCENE}/). Full reference: docs/index.md")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser("demo", help="the plant alone (no drives, no controller): a short table and a PNG of "
                                       "the workspace and a path; not the default job")
    demo.add_argument("--out", default="out", help="output directory (default: out)")
    demo.add_argument("--preset", default="thesis_sim", choices=("thesis_sim", "bench"),
                      help="the plant's parameters (default: thesis_sim)")
    build = sub.add_parser("build", help="build every FMU")
    build.add_argument("--out", default=None, help="output directory (default: fmus/build/); with --native, "
                                                   "fmus/build/native/")
    build.add_argument("--native", action="store_true",
                       help="build the native FMUs (C only, no Python in the importer; docs/native.md)")
    _fmi_version_option(build)
    sub.add_parser("list", help="print the scenes")
    run = sub.add_parser("run", help="run a scene: result.csv, metrics.json and plots")
    run.add_argument("scene", help="a scene name (see `parcosim list`)")
    run.add_argument("--mode", choices=("inprocess", "fmu", "compiled"), default="inprocess",
                     help="slaves in process (default), the built FMUs through fmpy, or the whole step loop "
                          "compiled (docs/benchmarks.md; falls back to in process with a warning)")
    run.add_argument("--coupling", choices=("gauss-seidel", "jacobi"), default="gauss-seidel",
                     help="gauss-seidel (default): each component reads what the ones before it computed this "
                          "step; jacobi: every input is the last step's output, a step of delay per connection "
                          "(the bench circle's e_ef grows to about 40 mm; docs/master.md)")
    run.add_argument("--out", default=None, help="output directory (default: out/SCENE)")
    run.add_argument("--fmu-dir", default=None,
                     help="where the FMUs of --mode fmu are, built when missing or stale (default: fmus/build/)")
    run.add_argument("--native", action="store_true",
                     help="with --mode fmu: the models that have a native FMU run as native FMUs built with "
                          "each instance's parameters (in FMU_DIR/native, default fmus/build/native; "
                          "docs/native.md)")
    run.add_argument("--retry-substeps", type=at_least(2, "retry_substeps"), default=None, metavar="N",
                     help="retry a refused step from the saved FMU states in N >= 2 sub-steps; saving every "
                          "state at every step makes the run much slower: use it after a refusal (docs/master.md)")
    run.add_argument("--drives-in-plant", type=at_least(1, "--drives-in-plant"), default=None, metavar="N",
                     help="integrate the drives inside the plant (ActuatedFiveBarPlant), RK4 N steps per "
                          "sample; 8 is 2.2e4x more accurate than separate drives (docs/actuated.md)")
    _replace_option(run)
    _fmi_version_option(run, "with --mode fmu --native: 2 (default); 3 is refused: the master's FMU back end is "
                              "FMI 2.0 (docs/native.md)")
    report = sub.add_parser("report", help="run the 16 bench scenes; markdown report beside the thesis' Tables 9-14")
    report.add_argument("--mode", choices=("inprocess", "fmu"), default="inprocess",
                        help="slaves in process (default) or the built FMUs through fmpy")
    report.add_argument("--out", default="out/report", help="output directory (default: out/report)")
    report.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="run the scenes on this dask scheduler (default: a local cluster)")
    report.add_argument("--workers", type=at_least(1, "--workers"), default=None, metavar="K",
                        help="local worker processes (default: one per core)")
    sweep = sub.add_parser("sweep", help="Monte Carlo: N runs of a scene with its plant and drives perturbed "
                                         "(dask.distributed; docs/sweeps.md)")
    sweep.add_argument("scene", help="a scene name (see `parcosim list`)")
    sweep.add_argument("--samples", type=at_least(1, "--samples"), required=True, metavar="N",
                       help="number of samples")
    sweep.add_argument("--uncertainty", type=non_negative("--uncertainty"), required=True, metavar="U",
                       help="uncertainty: 0.2 = masses, inertias, motor constants, friction +-20 %%; "
                            "lengths U/100, encoder zero U x 10 mrad (docs/sweeps.md)")
    sweep.add_argument("--seed", type=at_least(0, "--seed"), default=0, metavar="S",
                       help="random seed (default: 0)")
    sweep.add_argument("--distribution", choices=("uniform", "normal"), default=None,
                       help="uniform factor in [1-U, 1+U] or normal, sigma U, truncated at 3 sigma "
                            "(default: the perturb file's, else uniform)")
    sweep.add_argument("--perturb", default=None, metavar="FILE.toml",
                       help="per-parameter uncertainties (docs/sweeps.md)")
    sweep.add_argument("--mode", choices=_modes(), default="inprocess",
                       help="how each sample runs, as `parcosim run --mode` (default: inprocess)")
    sweep.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="an existing dask scheduler, e.g. tcp://host:8786 (default: a local cluster)")
    sweep.add_argument("--workers", type=at_least(1, "--workers"), default=None, metavar="K",
                       help="local worker processes (default: one per core)")
    sweep.add_argument("--stop-time", type=float, default=None, metavar="S",
                       help="end every run at S seconds, for quick checks; unreached metric windows give NaN "
                            "(default: the scene's end)")
    sweep.add_argument("--out", default=None, help="output directory (default: out/sweep_SCENE_U)")
    ssp = sub.add_parser("export-ssp", help="write a scene as an SSP 1.0 package for Jacobi masters "
                                            "(Ecos, libcosim, fmpy): control chain + plant")
    ssp.add_argument("scene", help="a scene name (see `parcosim list`)")
    ssp.add_argument("path", help="the .ssp file to write")
    ssp.add_argument("--fmu-dir", default=None,
                     help="where the component FMUs are, built when missing or stale (default: fmus/build/)")
    ssp.add_argument("--drives-in-plant", type=at_least(1, "--drives-in-plant"), default=None, metavar="N",
                     help="export the scene with its drives inside the plant, RK4 N steps per sample")
    ssp.add_argument("--per-component", action="store_true",
                     help="one FMU instance per component, stepped at a base step T/N with each sampled "
                          "component's sample phase set so that it tracks in Jacobi masters (docs/ssp.md)")
    ssp.add_argument("--substeps", type=int, default=None, metavar="N",
                     help="with --per-component: N base steps per 1 ms period (default: chosen from the chain)")
    ssp.add_argument("--internal-observer", action="store_true",
                     help="with --per-component: each drive estimates its own current (no obs1/obs2 instances)")
    ssp.add_argument("--native", action="store_true",
                     help="with --per-component: every instance a native FMU built with its parameters (C only, "
                          "no Python in the importer; in FMU_DIR/native, default fmus/build/native; docs/native.md)")
    _replace_option(ssp)
    fmu = sub.add_parser("export-fmu", help="write a scene's whole closed loop as one FMI 2.0 co-simulation FMU")
    fmu.add_argument("scene", help="a scene name (see `parcosim list`)")
    fmu.add_argument("path", help="the .fmu file to write")
    fmu.add_argument("--drives-in-plant", type=at_least(1, "--drives-in-plant"), default=None, metavar="N",
                     help="the scene with its drives inside the plant, RK4 N steps per sample")
    fmu.add_argument("--native", action="store_true",
                     help="a native FMU: the compiled loop in C, no Python in the importer (docs/native.md)")
    _fmi_version_option(fmu)
    _replace_option(fmu)
    trade = sub.add_parser("trade", help="speed against accuracy: sweep the settings, table and Pareto plot")
    trade.add_argument("scene", nargs="?", default=DEFAULT_SCENE,
                       help="a scene name (default: bench_circle_TCMDx)")
    trade.add_argument("--quick", action="store_true", help="1 s and fewer settings (under a minute)")
    trade.add_argument("--out", default="out/trade", help="output directory (default: out/trade)")
    plant = sub.add_parser("build-plant", help="build an FMU of a mechanism spec (TOML, docs/spec.md)")
    plant.add_argument("spec", help="a SPEC.toml file or a shipped spec's name (plant/specs/)")
    plant.add_argument("path", help="the .fmu file to write")
    ws = sub.add_parser("workspace", help="plot the workspace, singularity loci and the thesis' trajectories")
    ws.add_argument("mechanism", nargs="?", default="bench", help="a preset (thesis_sim, bench) or a SPEC.toml")
    ws.add_argument("--out", default="out/workspace", help="output directory (default: out/workspace)")
    ws.add_argument("--circle", action="append", default=[], metavar="CX,CY,R",
                    help="also check a 1 Hz circle like (7.23) around (CX, CY) of radius R [m] (repeatable)")
    sub.add_parser("identify-motor", help="identify DC motor parameters from u,i,omega data",
                   add_help=False)
    return parser


#: Each command's output: (attribute, its default; a file when ``is_file``), checked before any work.
_OUTPUTS = {"run": ("out", False), "sweep": ("out", False), "report": ("out", False), "trade": ("out", False),
            "demo": ("out", False), "workspace": ("out", False), "build": ("out", False),
            "export-ssp": ("path", True), "export-fmu": ("path", True), "build-plant": ("path", True)}


def _check_command(argv: list, parser) -> None:
    """Refuse a misspelled command, with the closest one, before argparse's 'invalid choice'."""
    commands = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)][0].choices
    if argv and not argv[0].startswith("-") and argv[0] not in commands:
        raise CommandError(f"unknown command {argv[0]!r}{suggestion(argv[0], commands)} "
                           f"(`parcosim --help` lists them)", head="parcosim")


def _check_scene(name: str) -> None:
    """Refuse an unknown scene naming the closest one."""
    from scenarios.scenes.catalogue import scene_names

    names = scene_names()
    if name not in names:
        raise CommandError(f"unknown scene {name!r}{suggestion(name, names)} "
                           f"(`parcosim list` prints the {len(names)} scenes)")


def _output(args) -> tuple:
    """(path, is_file) of the command's output, or (None, False)."""
    attribute, is_file = _OUTPUTS.get(args.command, (None, False))
    value = getattr(args, attribute, None) if attribute else None
    if args.command == "run" and value is None:
        value = Path("out") / _run_folder(args)
    elif args.command == "sweep" and value is None:
        value = _sweep_folder(args)
    elif args.command == "build" and value is None and args.native:
        from fmus.native.build import DEFAULT_NATIVE_OUT
        value = DEFAULT_NATIVE_OUT
    elif args.command == "build" and value is None:
        from fmus.export.build import DEFAULT_OUT
        value = DEFAULT_OUT
    return (Path(value), is_file) if value is not None else (None, False)


def _modes() -> tuple:
    from fmus.cosim.master import MODES

    return MODES


def _replace_option(parser) -> None:
    parser.add_argument("--replace", action="append", default=[], metavar="INSTANCE=PATH.fmu",
                        help="run the instance as this FMI 2.0 co-simulation FMU (repeatable; docs/master.md)")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] == "identify-motor":
        from motor.cli import identify_main
        return identify_main(argv[1:])
    if not argv:
        argv = ["run", DEFAULT_SCENE]
    made = None
    try:
        parser = _parser()
        _check_command(argv, parser)
        args = parser.parse_args(argv)
        if getattr(args, "scene", None) is not None:
            _check_scene(args.scene)
        if getattr(args, "native", False) and args.command == "run" and args.mode != "fmu":
            raise CommandError(f"--native runs native FMUs: it needs --mode fmu, not --mode {args.mode}")
        if getattr(args, "fmi_version", 2) != 2 and not args.native:
            raise CommandError(f"--fmi-version {args.fmi_version} is for the native FMUs: it needs --native")
        if args.command == "run" and args.fmi_version == 3:
            raise CommandError(FMI3_RUN_REFUSED)
        path, is_file = _output(args)
        if path is not None:
            check_output(path, is_file)
            made = first_missing(path.parent if is_file else path)
    except CommandError as exc:
        return _refuse(exc)
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        try:
            status = _busy(args) if args.command in _BUSY and sys.stderr.isatty() else _command(args)
        except KeyboardInterrupt:
            print("parcosim: interrupted", file=sys.stderr)
            return EXIT_INTERRUPTED
    if status == EXIT_REFUSED:
        remove_if_empty(made)
    return status


#: Commands that work for seconds to minutes with nothing to count: on a terminal they say so first.
_BUSY = {"export-ssp": "building the FMUs and the package", "export-fmu": "building the FMU",
         "build-plant": "building the FMU", "build": "building the FMUs", "workspace": "mapping the workspace",
         "demo": "simulating and drawing"}


def _busy(args) -> int:
    """Run the command with a status line on stderr, replaced by its output when it ends."""
    print(f"parcosim {args.command}: {_BUSY[args.command]} ...", end="", file=sys.stderr, flush=True)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = _command(args)
    print("\r\033[K", end="", file=sys.stderr, flush=True)
    sys.stdout.write(out.getvalue())
    return status


def _refuse(exc: Exception) -> int:
    """Print ``exc`` as the one line of a refused command; its exit status."""
    text = " ".join(str(exc).split())
    clear = "\r\033[K" if sys.stderr.isatty() else ""      # over a progress line, if one is shown
    print(f"{clear}{getattr(exc, 'head', 'parcosim: error')}: {text}", file=sys.stderr)
    return EXIT_REFUSED


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    clear = "\r\033[K" if sys.stderr.isatty() else ""
    print(f"{clear}parcosim: warning: {message}", file=sys.stderr)


def _command(args) -> int:
    try:
        if args.command == "demo":
            from scenarios.examples.plant_demo import run
            run(args.out, args.preset)
        elif args.command == "list":
            from scenarios.scenes.catalogue import get_scene, scene_names
            width = max(len(name) for name in scene_names())
            for name in scene_names():
                print(f"{name:{width}s} {get_scene(name).description}")
        elif args.command == "run":
            return _run(args)
        elif args.command == "report":
            from scenarios.batch.report import write_report
            print(write_report(args.out, args.mode, progress=progress_bar("report"), scheduler=args.scheduler,
                               workers=args.workers))
        elif args.command == "sweep":
            return _sweep(args)
        elif args.command == "export-ssp":
            if args.per_component:
                from scenarios.packaging.per_component import export_per_component
                print(export_per_component(_scene(args), args.path, args.fmu_dir, args.substeps,
                                           args.internal_observer, native=args.native))
            else:
                if args.substeps is not None or args.internal_observer or args.native:
                    raise ValueError("--substeps, --internal-observer and --native go with --per-component")
                from scenarios.packaging.chain import export_package
                print(export_package(_scene(args), args.path, args.fmu_dir))
        elif args.command == "export-fmu":
            if args.native:
                from fmus.native.loopbuild import export_native_fmu
                print(export_native_fmu(_scene(args).system, args.path, fmi_version=args.fmi_version))
            else:
                from fmus.systemfmu.export import export_fmu
                print(export_fmu(_scene(args).system, args.path))
        elif args.command == "trade":
            return _trade(args)
        elif args.command == "build-plant":
            from fmus.export.specfmu import build_plant_fmu
            print(build_plant_fmu(args.spec, args.path))
        elif args.command == "workspace":
            from scenarios.studies.workspace import plot_workspace
            circles = [tuple(float(v) for v in c.split(",")) for c in args.circle]
            if any(len(c) != 3 for c in circles):
                raise ValueError(f"--circle {args.circle}: write CX,CY,R in metres")
            print(plot_workspace(args.mechanism, args.out, circles=circles).summary())
        elif args.command == "build" and args.native:
            from fmus.native.build import DEFAULT_NATIVE_OUT, build_native_all
            for path in build_native_all(args.out or DEFAULT_NATIVE_OUT, args.fmi_version):
                print(path)
        elif args.command == "build":
            from fmus.export.build import DEFAULT_OUT, build_all
            for path in build_all(args.out or DEFAULT_OUT):
                print(path)
    except (ValueError, OSError, RuntimeError, zipfile.BadZipFile) as exc:
        return _refuse(exc)
    return 0


def progress_bar(label: str):
    """A one-line text progress bar on stderr: call it with the fraction done."""
    def show(fraction: float) -> None:
        filled = int(30 * fraction)
        end = "\n" if fraction >= 1.0 else ""
        print(f"\r{label} [{'#' * filled}{'.' * (30 - filled)}] {100 * fraction:5.1f} %", end=end,
              file=sys.stderr, flush=True)
    return show


def _scene(args):
    """The scene ``args.scene``, with its drives inside the plant if ``--drives-in-plant N``."""
    from scenarios.scenes.catalogue import get_scene
    from scenarios.scenes.transforms import drives_in_plant, with_fmu_files

    scene = get_scene(args.scene)
    if args.drives_in_plant is not None:
        if args.drives_in_plant < 1:
            raise ValueError(f"--drives-in-plant {args.drives_in_plant}: the RK4 steps per sample must be >= 1")
        scene = drives_in_plant(scene, substeps=args.drives_in_plant)
    return with_fmu_files(scene, _replacements(args.replace))


def _replacements(items) -> dict:
    """``["drive1=a.fmu", ...]`` -> ``{"drive1": "a.fmu"}``."""
    result = {}
    for item in items:
        instance, eq, path = item.partition("=")
        if not eq or not instance or not path:
            raise ValueError(f"--replace {item}: write INSTANCE=PATH.fmu")
        if instance in result:
            raise ValueError(f"--replace {instance}: given twice")
        if Path(path).is_file() and not _is_fmu_archive(path):
            raise ValueError(f"--replace {item}: {path} is not an FMU (no zip archive with a modelDescription.xml)")
        result[instance] = path
    return result


def _is_fmu_archive(path) -> bool:
    """Whether ``path`` is a zip archive holding a modelDescription.xml."""
    try:
        with zipfile.ZipFile(path) as archive:
            return "modelDescription.xml" in archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return False


def _run_folder(args) -> str:
    """``parcosim run``'s default folder name under out/."""
    return args.scene + ("" if args.drives_in_plant is None else "_drives_in_plant") + \
        ("_replaced" if args.replace else "") + ("_native" if args.native else "")


def _run(args) -> int:
    from scenarios.run.runner import run_scene

    scene = _scene(args)
    if args.native:
        from fmus.native.build import DEFAULT_NATIVE_OUT
        from fmus.native.run import with_native_fmus
        scene = with_native_fmus(scene, Path(args.fmu_dir) / "native" if args.fmu_dir else DEFAULT_NATIVE_OUT)
    out = Path(args.out) if args.out else Path("out") / _run_folder(args)
    bar = progress_bar(scene.name) if sys.stderr.isatty() else None
    if bar is not None:
        print(f"{scene.name}: loading and initialising ({args.mode})...", end="", file=sys.stderr, flush=True)
    outcome = run_scene(scene, mode=args.mode, out_dir=out, coupling=args.coupling,
                        fmu_dir=args.fmu_dir, progress=bar, retry_substeps=args.retry_substeps)
    m, error = outcome.metrics, outcome.result.error
    if error is not None:
        so_far = (f"; recorded so far ({len(outcome.result.time)} rows): {out}" if error.kind is RunStatus.INTERRUPTED
                  else f" (recorded so far: {out})")
        print(f"parcosim: {error}{so_far}", file=sys.stderr)
        return EXIT_STATUS[error.kind]
    if args.retry_substeps is not None and not m["retried_steps"]:
        print("parcosim: note: no step was refused, so --retry-substeps retried nothing; it only slowed the run "
              "(every state saved at every step): leave it out unless a step is refused", file=sys.stderr)
    compiled = f", compiled in {m['compile_s']:.2f} s" if "compile_s" in m else ""
    speed = f"{m['wall_s']:.2f} s wall ({m['realtime_factor']:.1f}x real time{compiled}) -> {out}"
    if "peak_pitch_deg" in m:     # a wheeled pendulum's scene: its own metrics
        from scenarios.scenes.pendulum import pendulum_line

        print(f"{scene.name} [{m['mode']}]: {pendulum_line(m)}, {speed}")
        return 0
    settled = (f" (settled {m['t_settle_s']:.2f} s after the stop)" if m.get("settled")
               else " (not settled)" if math.isfinite(m.get("e_ss_mm", math.nan)) else "")
    print(f"{scene.name} [{m['mode']}]: e_ef {m['e_ef_mm']:.4g} mm, tau_ef {m['tau_ef_Nm']:.4g} N m, "
          f"e_ss {m['e_ss_mm']:.4g} mm{settled}, {speed}")
    return 0


def _sweep_folder(args) -> str:
    """``parcosim sweep``'s default folder."""
    return f"out/sweep_{args.scene}_U{args.uncertainty:g}"


def _sweep(args) -> int:
    from scenarios.batch.sweep import run_sweep

    out = args.out or _sweep_folder(args)
    sweep = run_sweep(args.scene, args.samples, args.uncertainty, seed=args.seed, distribution=args.distribution,
                      perturb=args.perturb, mode=args.mode, out_dir=out, scheduler=args.scheduler,
                      workers=args.workers, stop_time=args.stop_time, progress=progress_bar(f"sweep {args.scene}"))
    s = sweep.summary
    e = s["e_ef_mm"]
    median = f"e_ef median {e['median']:.4g} mm (5-95 %: {e['p05']:.4g}-{e['p95']:.4g})" if e["n"] else "no e_ef"
    print(f"{sweep.scene} U={args.uncertainty:g}: {s['samples']} samples ({len(sweep.computed)} run now), "
          f"{s['completed']} completed, {s['failed']} failed; {median} -> {out}/sweep.csv")
    if not s["completed"]:
        first = next(r["error"] for r in sweep.rows if not r["completed"])
        print(f"parcosim: every sample failed; the first: {first}", file=sys.stderr)
        return EXIT_STATUS[RunStatus.FAILED]
    return 0


def _trade(args) -> int:
    from scenarios.scenes.pendulum import PENDULUM_SCENES
    from scenarios.studies.trade import run_trade

    if args.scene in PENDULUM_SCENES:   # the pendulum's own study (scenarios/studies/pendulum_trade.py)
        from scenarios.studies.pendulum_trade import run_pendulum_trade

        report = run_pendulum_trade(args.scene, quick=args.quick, out_dir=args.out,
                                    progress=lambda line: print(line, file=sys.stderr, flush=True))
        settings = ", ".join(f"{r['setting']} {r['wall_s']:.2f} s" for r in report["fidelity"])
        print(f"{args.scene}: {settings} -> {args.out}/trade.md")
        return 0
    trade = run_trade(args.scene, quick=args.quick, out_dir=args.out,
                      progress=lambda line: print(line, file=sys.stderr, flush=True))
    base = trade.row("defaults")
    front = ", ".join(r["setting"] for r in trade.rows if r["pareto"])
    print(f"{trade.scene} 0-{trade.stop_time:g} s: defaults {base['wall_s']:.2f} s wall, "
          f"RMS deviation {base['rms_err_m']:.2g} m; front: {front} -> {args.out}/trade.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
