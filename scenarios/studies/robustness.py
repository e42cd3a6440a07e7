"""The robustness study of docs/sweeps.md: the eight strategies x circle/triangle x U, by sweeps.

``python -m scenarios.studies.robustness [--samples 100] [--stages 25,50] [--uncertainties 0.1,0.2,0.4]
[--workers K] [--scheduler ADDRESS] [--mode M] [--out out/robustness] [--render-only]``

Every (scene, U) is one :func:`scenarios.batch.sweep.run_sweep` into ``OUT/<scene>/U<U>/``, all on one
cluster; ``--stages`` first brings every sweep to each stage's sample count, so a study
stopped early has the same number of samples everywhere (and, started again, computes only
what is missing).  The nominal run of each scene (U = 0) is ``OUT/<scene>/U0/``.  Then
``OUT/robustness.md`` (tables) and ``OUT/robustness.png`` (violins) are written from the
csv files found, whatever their sample counts.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from scenarios.batch.engine import open_client
from scenarios.batch.report import PAIRS
from scenarios.batch.sweep import columns, read_rows, run_sweep
from scenarios.scenes.perturb import perturbable
from scenarios.scenes.catalogue import get_scene

STRATEGIES = ("PDq", "PDMDq", "TCq", "TCMDq", "PDx", "PDMDx", "TCx", "TCMDx")
KINDS = ("circle", "triangle")
UNCERTAINTIES = (0.1, 0.2, 0.4)


def _dir(out: Path, scene: str, U: float) -> Path:
    return out / scene / f"U{U:g}"


def run_study(out, samples=100, stages=(), uncertainties=UNCERTAINTIES, kinds=KINDS, workers=None,
              scheduler=None, mode="inprocess", say=print) -> None:
    """Run (or continue) every sweep of the study; see the module docstring."""
    out = Path(out)
    scenes = [f"bench_{k}_{s}" for k in kinds for s in STRATEGIES]
    with open_client(scheduler, workers) as client:
        for scene in scenes:
            run_sweep(scene, 1, 0.0, mode=mode, out_dir=_dir(out, scene, 0.0), client=client, plots=False)
        for n in [*[s for s in stages if s < samples], samples]:
            for U in uncertainties:
                for scene in scenes:
                    start = time.perf_counter()
                    sweep = run_sweep(scene, n, U, mode=mode, out_dir=_dir(out, scene, U), client=client, plots=False)
                    say(f"{scene} U={U:g} N={n}: {len(sweep.computed)} run in {time.perf_counter() - start:.1f} s, "
                        f"{sweep.summary['failed']} failed")


def load(out, kinds=KINDS, uncertainties=UNCERTAINTIES) -> dict:
    """(kind, strategy, U) -> rows of the sweep.csv found (U = 0.0: the nominal run)."""
    out = Path(out)
    found = {}
    for kind in kinds:
        for s in STRATEGIES:
            scene = f"bench_{kind}_{s}"
            header = columns([p.name for p in perturbable(get_scene(scene))])
            for U in (0.0, *uncertainties):
                path = _dir(out, scene, U) / "sweep.csv"
                if path.exists():
                    found[kind, s, U] = read_rows(path, header)
    return found


def _stat(rows, metric, q):
    v = [r[metric] for r in rows if r["completed"] and math.isfinite(r[metric])]
    return float(np.percentile(v, q)) if v else float("nan")


def render(found: dict, uncertainties=UNCERTAINTIES, command: str = "") -> str:
    """robustness.md: per trajectory and U, each strategy's e_ef and τ_ef distribution."""
    lines = ["# Robustness of the eight strategies (sweeps)", ""]
    if command:
        lines += [f"`{command}`", ""]
    for kind in KINDS:
        for U in uncertainties:
            present = [s for s in STRATEGIES if (kind, s, U) in found]
            if not present:
                continue
            n = sorted({len(found[kind, s, U]) for s in present})
            lines += [f"## {kind}, U = {U:g} ({'/'.join(map(str, n))} samples per strategy)", "",
                      "| strategy | e_ef nominal mm | e_ef median | e_ef 5-95 % | median / nominal | τ_ef nominal N m | "
                      "τ_ef median | τ_ef 95 % | e_ss median mm | failed |", "|---|---|---|---|---|---|---|---|---|---|"]
            for s in present:
                rows, nominal = found[kind, s, U], found.get((kind, s, 0.0), [])
                e0 = nominal[0]["e_ef_mm"] if nominal else float("nan")
                t0 = nominal[0]["tau_ef_Nm"] if nominal else float("nan")
                em = _stat(rows, "e_ef_mm", 50)
                failed = sum(not r["completed"] for r in rows)
                lines.append(f"| {s} | {e0:.3f} | {em:.3f} | {_stat(rows, 'e_ef_mm', 5):.3f}-"
                             f"{_stat(rows, 'e_ef_mm', 95):.3f} | {em / e0:.2f} | {t0:.4f} | "
                             f"{_stat(rows, 'tau_ef_Nm', 50):.4f} | {_stat(rows, 'tau_ef_Nm', 95):.4f} | "
                             f"{_stat(rows, 'e_ss_mm', 50):.3f} | {failed} |")
            lines += [""] + _reading(found, kind, U, present) + [""]
    return "\n".join(lines)


def _reading(found, kind, U, present) -> list:
    p95 = {s: _stat(found[kind, s, U], "e_ef_mm", 95) for s in present}
    ranked = sorted((s for s in present if math.isfinite(p95[s])), key=p95.get)
    out = [f"Ranking by the 95 % quantile of e_ef, best first: {', '.join(ranked)}."]
    md = []
    for pure, hybrid in PAIRS:
        if (kind, pure, U) in found and (kind, hybrid, U) in found:
            a = _stat(found[kind, pure, U], "e_ef_mm", 50)
            b = _stat(found[kind, hybrid, U], "e_ef_mm", 50)
            md.append(f"{pure}→{hybrid} {100 * (b - a) / a:+.0f} %")
    if md:
        out.append("Median e_ef change from adding the sliding-mode term: " + ", ".join(md) + ".")
    return out


def plot(found: dict, path: Path, uncertainties=UNCERTAINTIES) -> Path:
    """robustness.png: per trajectory and U, violins of e_ef and τ_ef per strategy."""
    from scenarios.batch.sweep_plots import plot_groups

    panels = {}
    for kind in KINDS:
        for U in uncertainties:
            groups = {s: found[kind, s, U] for s in STRATEGIES if (kind, s, U) in found}
            if groups:
                panels[f"{kind}, U = {U:g}"] = groups
    return plot_groups(panels, path)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m scenarios.studies.robustness", description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100)
    parser.add_argument("--stages", default="", help="comma-separated sample counts to reach first, e.g. 25,50")
    parser.add_argument("--uncertainties", default=",".join(f"{u:g}" for u in UNCERTAINTIES))
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--mode", default="inprocess", choices=("inprocess", "compiled", "fmu"),
                        help="how each run steps (compiled: same results, ~20x faster stepping)")
    parser.add_argument("--scheduler", default=None)
    parser.add_argument("--out", default="out/robustness")
    parser.add_argument("--render-only", action="store_true", help="only write the tables and plot from the csv files")
    args = parser.parse_args(argv)
    uncertainties = tuple(float(u) for u in args.uncertainties.split(","))
    stages = tuple(int(s) for s in args.stages.split(",") if s)
    if not args.render_only:
        run_study(args.out, args.samples, stages, uncertainties, workers=args.workers, scheduler=args.scheduler,
                  mode=args.mode,
                  say=lambda line: print(line, file=sys.stderr, flush=True))
    found = load(args.out, uncertainties=uncertainties)
    out = Path(args.out)
    (out / "robustness.md").write_text(render(found, uncertainties, "python -m scenarios.studies.robustness "
                                              + " ".join(sys.argv[1:] if argv is None else argv)))
    plot(found, out / "robustness.png", uncertainties)
    print(out / "robustness.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
