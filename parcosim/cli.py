"""The ``parcosim`` command.

Every subcommand is a thin shell over a documented Python call:

=====================  ==============================================
``parcosim``           ``scenarios.plant_demo.run("out")`` (the default job)
``parcosim demo``      same, with ``--out`` and ``--preset``
``parcosim build``     ``fmus.build.build_all(out_dir)``
``parcosim identify-motor``  ``motor.cli.identify_main(argv)``
=====================  ==============================================

Errors end the command with exit status 2 and one readable line on stderr.
"""
from __future__ import annotations

import argparse
import sys


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="parcosim", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command")
    demo = sub.add_parser("demo", help="plant demo: a short table and a PNG of the workspace and a path")
    demo.add_argument("--out", default="out", help="output directory (default: out)")
    demo.add_argument("--preset", default="thesis_sim", help="thesis_sim or bench")
    build = sub.add_parser("build", help="build every FMU")
    build.add_argument("--out", default=None, help="output directory (default: fmus/build/)")
    sub.add_parser("identify-motor", help="identify DC motor parameters from u,i,omega data",
                   add_help=False)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] == "identify-motor":
        from motor.cli import identify_main
        return identify_main(argv[1:])
    args = _parser().parse_args(argv)
    try:
        if args.command in (None, "demo"):
            from scenarios.plant_demo import run
            run(getattr(args, "out", "out"), getattr(args, "preset", "thesis_sim"))
        elif args.command == "build":
            from fmus.build import DEFAULT_OUT, build_all
            for path in build_all(args.out or DEFAULT_OUT):
                print(path)
    except (ValueError, OSError, RuntimeError) as exc:
        print(f"parcosim: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
