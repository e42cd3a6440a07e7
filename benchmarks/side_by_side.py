"""Two trees' closed-loop speed, measured side by side: bench_master run alternately in each.

    python -m benchmarks.side_by_side --base /work/wt-base --base-python /venv-with-numba/bin/python \
        --pairs 4 --repeats 5 --out benchmarks/results/side_by_side
    python -m benchmarks.side_by_side --report benchmarks/results/side_by_side

The machine's speed changes (docs/benchmarks.md, "The machine's two speeds"; this host ran the
same commit 1.9-2.3x slower than on the day an issue quoted its figures), so a goal stated as
"N x real time, today M x" is checked as a ratio: this tree's real-time factor over the base
tree's, each pair of processes run back to back, base first.  ``--base`` is a checkout (a
``git worktree add --detach DIR COMMIT``) and ``--base-python`` the interpreter with that
checkout's dependencies; each run's JSON (bench_master ``--json``) is kept in ``--out``.
Printed: per case, each pair's medians and ratio, and the median of the ratios.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: The cases compared (the base tree's bench_master runs all it has; these are in both).
CASES = ("inprocess", "fmu", "floor_fmu", "compiled")


def run_pair(base: Path, base_python: str, out: Path, k: int, repeats: int) -> None:
    """Pair ``k``: bench_master in the base tree, then in this one, each writing its JSON to ``out``."""
    for side, tree, python, extra in (("base", base, base_python, []),
                                      ("this", ROOT, sys.executable, ["--cases", ",".join(CASES)])):
        env = dict(os.environ, PYTHONPATH=str(tree))
        subprocess.run([python, "benchmarks/bench_master.py", "--repeats", str(repeats), "--no-breakdown",
                        "--json", str(out / f"{side}_{k}.json"), *extra],
                       cwd=tree, env=env, check=True, stdout=subprocess.DEVNULL)


def medians(path: Path) -> dict:
    """case -> median real-time factor of one bench_master JSON."""
    runs = json.loads(path.read_text())["runs"]
    return {case: statistics.median(r["rtf"] for r in runs[case]) for case in CASES if case in runs}


def report(out: Path) -> str:
    """The table of every pair in ``out``, as Markdown."""
    pairs = sorted(int(p.stem.split("_")[1]) for p in out.glob("this_*.json") if (out / f"base_{p.stem[5:]}.json").exists())
    if not pairs:
        raise SystemExit(f"side_by_side: no pairs (base_K.json and this_K.json) in {out}")
    read = {k: (medians(out / f"base_{k}.json"), medians(out / f"this_{k}.json")) for k in pairs}
    lines = ["| case | " + " | ".join(f"pair {k}: base -> this" for k in pairs) + " | median ratio |",
             "|---|" + "---:|" * (len(pairs) + 1)]
    for case in CASES:
        cells, ratios = [], []
        for k in pairs:
            b, t = read[k][0].get(case), read[k][1].get(case)
            if b is None or t is None:
                cells.append("")
                continue
            ratios.append(t / b)
            cells.append(f"{b:.1f}x -> {t:.1f}x ({t / b:.2f})")
        if ratios:
            lines.append(f"| {case} | " + " | ".join(cells) + f" | {statistics.median(ratios):.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.side_by_side", description=__doc__.splitlines()[0])
    parser.add_argument("--base", type=Path, help="the base tree (a checkout of the commit compared against)")
    parser.add_argument("--base-python", default=sys.executable, help="the base tree's Python (default: this one)")
    parser.add_argument("--pairs", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=5, help="bench_master rounds per run")
    parser.add_argument("--out", type=Path, required=True, help="folder of the runs' JSON files")
    parser.add_argument("--report", action="store_true", help="only print the table of the runs in --out")
    args = parser.parse_args(argv)
    if not args.report:
        if args.base is None or not (args.base / "benchmarks" / "bench_master.py").is_file():
            parser.error(f"--base {args.base}: not a tree with benchmarks/bench_master.py")
        args.out.mkdir(parents=True, exist_ok=True)
        for k in range(1, args.pairs + 1):
            run_pair(args.base, args.base_python, args.out, k, args.repeats)
    print(report(args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
