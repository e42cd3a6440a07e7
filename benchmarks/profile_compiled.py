"""Where the compiled loop's time goes: a workload for ``perf record`` and the shares of its report.

    gcc -std=c11 -O3 -fno-math-errno -g -fPIC -shared -ffp-contract=off -Ikernels/src kernels/src/*.c \\
        -DPC_SOURCES_HASH='"g"' -o /tmp/kernels_g.so -lm          # the kernels with symbols
    PARCOSIM_KERNELS_LIB=/tmp/kernels_g.so perf record -o /tmp/loop.data \\
        python benchmarks/profile_compiled.py --runs 30           # bench_circle_TCMDx compiled, 30 times
    python benchmarks/profile_compiled.py --report /tmp/loop.data --library kernels_g.so

The workload runs ``--scene`` with ``simulate(system, mode="compiled")`` ``--runs`` times (the
Python set-up of each run is in the samples too: the report keeps only the kernels' library
and libm).  ``--report`` prints each symbol's share of the samples in those two, i.e. of the
time spent in the C kernels and the loop.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: A line of ``perf report --sort dso,symbol --stdio``: share, object, symbol.
_LINE = re.compile(r"\s+([\d.]+)%\s+(\S+)\s+\[\.\]\s+(\S+)")


def run(scene: str, runs: int) -> None:
    """The workload: ``scene`` compiled ``runs`` times."""
    sys.path.insert(0, str(ROOT))
    from fmus.cosim.master import simulate
    from scenarios.scenes.catalogue import get_scene

    system = get_scene(scene).system
    for _ in range(runs):
        simulate(system, mode="compiled")


def shares(perf_data: str, library: str, top: int) -> list:
    """(share in %, 'lib' or 'libm', symbol) of the ``top`` symbols of ``library`` and libm in
    ``perf_data``, shares of their sum."""
    out = subprocess.run(["perf", "report", "-i", perf_data, "--no-children", "--sort", "dso,symbol", "--stdio"],
                         capture_output=True, text=True, check=True).stdout
    rows = [(float(m[1]), m[2], m[3]) for m in map(_LINE.match, out.splitlines())
            if m and (m[2] == library or m[2].startswith("libm"))]
    total = sum(r[0] for r in rows) or 1.0
    return [(100.0 * pct / total, "libm" if dso.startswith("libm") else "lib", sym) for pct, dso, sym in rows[:top]]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="bench_circle_TCMDx")
    parser.add_argument("--runs", type=int, default=30)
    parser.add_argument("--report", metavar="PERF_DATA", help="print the shares of a perf record of the workload")
    parser.add_argument("--library", default="libparcosim_kernels.so", help="file name of the kernels' library")
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args(argv)
    if args.report:
        for pct, kind, sym in shares(args.report, args.library, args.top):
            print(f"{pct:5.1f} %  {kind:4}  {sym}")
        return 0
    run(args.scene, args.runs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
