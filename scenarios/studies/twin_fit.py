"""Calibrate the bench twin on the thesis' circle, then predict the triangle without refitting.

    python -m scenarios.studies.twin_fit fit [--points 64 --starts 4 --maxfev 120 --workers 2]
                                                      # fit on Tables 9, 11, 13; writes scenarios/scenes/bench_twin.toml
    python -m scenarios.studies.twin_fit report [--out DIR | --docs]  # runs the 16 twin scenes x 5 seeds;
                                                      # out/twin/ (--docs: docs/) twin.md, twin.png
    python -m scenarios.studies.twin_fit                      # both

or in Python: ``fit(points=..., starts=...)`` then ``write_twin_report(out_dir)``.  Only ``--docs``
(``write_twin_report("docs")``) changes the repository's docs/.

The fit reads only the circle's published numbers (:data:`scenarios.batch.report.THESIS_BENCH`
``["circle"]``: Tables 9 and 13; :data:`scenarios.batch.report.THESIS_MD_CHANGE` ``["circle"]``:
Table 11).  Its loss (:func:`loss`) is the mean squared log-ratio of ours to the bench's:
per strategy e_ef, τ_ef and (weight :data:`E_SS_WEIGHT`) e_ss, per sliding-mode pair
Table 11's ratios (1 + change/100) of e_ef and τ_ef.  Log-ratios weigh a factor of 2 the
same on 0.04 mm as on 3 mm.  Ours are the means over the noise seeds
:data:`scenarios.scenes.twin.FIT_SEEDS`, fixed before the fit, so the loss is a deterministic
function of the six parameters.  The search is global, then local, in the box of
:data:`scenarios.scenes.twin.PARAMETERS` scaled to [0, 1]^6: the loss at :data:`START` (the
identified motors with the LuGre presets: the plain bench plus delay and PWM) and at
scrambled Sobol points (:func:`screen`), then bounded Nelder-Mead (scipy) from the best few
(:func:`descend`); stick-slip makes the loss rough at small scales, so one descent from
one start stops in the first dip it finds.  Every run is in
``mode="compiled"``.  The triangle's tables are read only by the report, after the fit.
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from scenarios.batch.report import PAIRS, THESIS_BENCH, THESIS_MD_CHANGE, side_section
from scenarios.run.runner import run_scene
from scenarios.scenes.twin import (FIT_SEEDS, KINDS, PARAMETERS, SPREAD_SEEDS, TWIN_FILE, Twin, bench_real, load_twin, read_fit,
                   write_twin)

ROOT = Path(__file__).resolve().parents[2]
#: The thesis' eight strategies in its tables' order.
ORDER = ("PDq", "PDMDq", "TCq", "TCMDq", "PDx", "PDMDx", "TCx", "TCMDx")
#: Where the search starts: the identified motors, the drive's LuGre presets, no offset,
#: no noise, the exact model (scenarios.scenes.twin.Twin's defaults).
START = Twin()
#: Weight of e_ss in the loss: one number per strategy read once on the bench, below one
#: encoder count for the sliding-mode laws, so less certain than the RMS values.
E_SS_WEIGHT = 0.5
#: Errors below this are compared as this [mm] (a fifth of one encoder count at the end
#: effector): below it a log-ratio measures noise.
E_FLOOR_MM = 0.01
METRICS = ("e_ef_mm", "tau_ef_Nm", "e_ss_mm")
#: Seed of the fit's scrambled Sobol points (fixed, like the noise seeds, before fitting).
SOBOL_SEED = 2019
#: First simplex of each descent: steps of this fraction of each parameter's range.
SIMPLEX_STEP = 0.1


def run_twin(twin: Twin, kind: str, seeds=SPREAD_SEEDS, strategies=ORDER) -> dict:
    """strategy -> seed -> metrics of the twin scene ``bench_real_<kind>_<strategy>``
    (compiled mode, serial in this process)."""
    runs = {}
    for s in strategies:
        runs[s] = {}
        for seed in seeds:
            runs[s][seed] = run_scene(bench_real(s, kind, twin, seed), mode="compiled", plots=False).metrics
    return runs


def mean_metrics(runs: dict) -> dict:
    """strategy -> metric -> mean over the seeds (NaN if a run stopped early)."""
    out = {}
    for s, by_seed in runs.items():
        out[s] = {}
        for key in METRICS:
            values = [m[key] if m["completed"] else math.nan for m in by_seed.values()]
            out[s][key] = float(np.mean(values))
    return out


def _log_ratio(ours, bench, floor=0.0):
    return math.log(max(ours, floor) / max(bench, floor))


def loss(means: dict, kind: str = "circle") -> float:
    """Mean squared log-ratio of ``means`` (strategy -> metric -> value) to the thesis'
    ``kind`` tables (module docstring); inf for a run that stopped early (a metric that is
    not finite and positive)."""
    terms = []
    for s, (e_ef, tau_ef, _ex, _ey, e_ss) in THESIS_BENCH[kind].items():
        m = means[s]
        if not all(math.isfinite(m[k]) and m[k] > 0 for k in METRICS):
            return math.inf
        terms += [_log_ratio(m["e_ef_mm"], e_ef) ** 2, _log_ratio(m["tau_ef_Nm"], tau_ef) ** 2,
                  E_SS_WEIGHT * _log_ratio(m["e_ss_mm"], e_ss, E_FLOOR_MM) ** 2]
    for pure, hybrid in PAIRS:
        de, dt = THESIS_MD_CHANGE[kind][pure]
        terms += [(math.log(means[hybrid]["e_ef_mm"] / means[pure]["e_ef_mm"]) - math.log(1 + de / 100)) ** 2,
                  (math.log(means[hybrid]["tau_ef_Nm"] / means[pure]["tau_ef_Nm"]) - math.log(1 + dt / 100)) ** 2]
    return float(np.mean(terms))


def _to_unit(twin: Twin) -> np.ndarray:
    return np.array([(getattr(twin, n) - b.low) / (b.high - b.low) for n, b in PARAMETERS.items()])


def _from_unit(u) -> Twin:
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    return Twin(**{n: float(b.low + x * (b.high - b.low)) for x, (n, b) in zip(u, PARAMETERS.items())})


def evaluate(u, seeds=FIT_SEEDS) -> tuple:
    """(loss, twin) at the point ``u`` of the unit box (:func:`loss` of the eight circle runs,
    seed means).  Module level so that worker processes can run it."""
    twin = _from_unit(u)
    return loss(mean_metrics(run_twin(twin, "circle", seeds))), twin


def screen(points: int = 64, seeds=FIT_SEEDS, workers: int = 1, log=print) -> list:
    """[(loss, twin)] of :data:`START` and ``points`` scrambled Sobol points of the unit box
    (seed :data:`SOBOL_SEED`, fixed), best first: the global part of :func:`fit`."""
    from scipy.stats import qmc

    units = [_to_unit(START)] + list(qmc.Sobol(len(PARAMETERS), scramble=True, seed=SOBOL_SEED).random(points))
    results = _map(evaluate, units, seeds, workers)
    for i, (value, twin) in enumerate(results):
        log(f"screen {i:4d} loss {value:.5f}  " + _text(twin))
    return sorted(results, key=lambda item: item[0])


def descend(start: Twin, maxfev: int, seeds=FIT_SEEDS, log=print) -> tuple:
    """(best loss, twin, evaluations, scipy's message): bounded Nelder-Mead in the unit box
    from ``start``, first simplex of steps :data:`SIMPLEX_STEP` (the local part of :func:`fit`)."""
    from scipy.optimize import minimize

    history = []

    def objective(u):
        value, twin = evaluate(u, seeds)
        history.append((value, twin))
        log(f"  descend {len(history):4d} loss {value:.5f}  " + _text(twin))
        return value

    u0 = _to_unit(start)
    simplex = [u0] + [np.clip(u0 + SIMPLEX_STEP * np.eye(len(u0))[i] * (1 if u0[i] < 1 - SIMPLEX_STEP else -1), 0, 1)
                      for i in range(len(u0))]
    result = minimize(objective, u0, method="Nelder-Mead", bounds=[(0.0, 1.0)] * len(u0),
                      options={"maxfev": maxfev, "initial_simplex": np.array(simplex), "xatol": 0.002,
                               "fatol": 1e-4})
    best_loss, best = min(history, key=lambda item: item[0])
    return best_loss, best, len(history), result.message


def _descend_task(start, maxfev, seeds):
    return descend(start, maxfev, seeds, log=lambda text: print(text, flush=True))


def fit(points: int = 64, starts: int = 4, maxfev: int = 120, seeds=FIT_SEEDS, workers: int = 2,
        path: Path = TWIN_FILE, log=print) -> Twin:
    """Fit the twin's parameters on the circle (module docstring): :func:`screen` ``points``
    Sobol points, then :func:`descend` (at most ``maxfev`` evaluations) from the ``starts`` best;
    write the best twin of all to ``path``; return it.  ``workers`` processes share the work."""
    t0 = time.perf_counter()
    screened = screen(points, seeds, workers, log)
    starts_from = [twin for _, twin in screened[:starts]]
    descents = _map(_descend_task, starts_from, (maxfev, seeds), workers, star=True)
    for i, (value, twin, n, message) in enumerate(descents):
        log(f"descent {i}: loss {screened[i][0]:.5f} -> {value:.5f} in {n} evaluations ({message})  " + _text(twin))
    best_loss, best, _n, _m = min(descents, key=lambda item: item[0])
    start_loss = next(value for value, twin in screened if twin == START)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    write_twin(best, {"loss": best_loss, "start_loss": start_loss,
                      "evaluations": len(screened) + sum(d[2] for d in descents),
                      "optimizer": f"{points} scrambled Sobol points (seed {SOBOL_SEED}) and the start, then bounded "
                                   f"scipy Nelder-Mead (maxfev {maxfev}) from the {starts} best",
                      "screen_best": [round(v, 5) for v, _ in screened[:starts]],
                      "descent_losses": [round(d[0], 5) for d in descents],
                      "descent_ends": [list(d[1].values().values()) for d in descents],
                      "seeds": list(seeds), "tables": "circle: Tables 9, 11, 13 (scenarios.batch.report)",
                      "wall_s": round(time.perf_counter() - t0, 1), "commit": commit}, path)
    return best


def _text(twin: Twin) -> str:
    return "  ".join(f"{k} {v:.4g}" for k, v in twin.values().items())


def _map(function, items, extra, workers: int, star: bool = False) -> list:
    """[function(item, *extra)] (``extra`` a tuple if ``star``, else one argument), on a local
    dask cluster of ``workers`` processes when more than one (:func:`scenarios.batch.engine.open_client`,
    the sweeps' and the report's)."""
    extra = tuple(extra) if star else (extra,)
    if workers <= 1:
        return [function(item, *extra) for item in items]
    from scenarios.batch.engine import open_client

    with open_client(workers=workers) as client:
        futures = client.map(function, items, *[[e] * len(items) for e in extra], pure=False)
        return client.gather(futures)


def predict(twin: Twin | None = None, seeds=SPREAD_SEEDS) -> dict:
    """kind -> strategy -> seed -> metrics of the 16 twin scenes (the fitted circle and the
    predicted triangle) for every seed of ``seeds``."""
    twin = load_twin() if twin is None else twin
    return {kind: run_twin(twin, kind, seeds) for kind in KINDS}


#: Relative steps of ``friction_scale`` of the sensitivity runs (:func:`sensitivity`).
SENSITIVITY_STEPS = (-2e-3, -1e-3, 1e-3, 2e-3)


def sensitivity(twin: Twin | None = None) -> dict:
    """kind -> strategy -> step -> metrics with ``friction_scale`` moved by ``step`` (relative,
    :data:`SENSITIVITY_STEPS`), seed ``SPREAD_SEEDS[0]``: how much of a run's numbers is the
    detail of stick-slip (a change of 0.1 % is far below what the fit can resolve)."""
    twin = load_twin() if twin is None else twin
    out = {}
    for kind in KINDS:
        out[kind] = {}
        for s in ORDER:
            out[kind][s] = {}
            for step in SENSITIVITY_STEPS:
                moved = Twin(**{**twin.values(), "friction_scale": twin.friction_scale * (1 + step)})
                out[kind][s][step] = run_twin(moved, kind, SPREAD_SEEDS[:1], (s,))[s][SPREAD_SEEDS[0]]
    return out


def _spread(by_seed: dict, key: str) -> tuple:
    values = np.array([m[key] for m in by_seed.values()], dtype=float)
    return float(np.mean(values)), float(np.min(values)), float(np.max(values))


def descent_ends(fit_info: dict) -> list:
    """[(loss, twin)] of the ends of the fit's descents (``[fit]`` ``descent_losses`` and
    ``descent_ends``, parameters in :data:`scenarios.scenes.twin.PARAMETERS` order); [] if absent."""
    ends = fit_info.get("descent_ends", [])
    return [(loss_, Twin(**dict(zip(PARAMETERS, values)))) for loss_, values in zip(fit_info.get("descent_losses", []), ends)]


def calibration_spread(fit_info: dict, seed: int = SPREAD_SEEDS[0]) -> list:
    """[(loss, twin, kind -> strategy -> metrics)] for each end of the fit's descents, both
    trajectories, noise seed ``seed``: how much the prediction depends on which of the nearly
    equal circle fits is taken."""
    return [(value, twin, {kind: {s: by_seed[seed] for s, by_seed in run_twin(twin, kind, (seed,)).items()}
                           for kind in KINDS}) for value, twin in descent_ends(fit_info)]


def render(runs: dict, twin: Twin, fit_info: dict, moved: dict | None = None, spread: list | None = None) -> str:
    """docs/twin.md from the runs of :func:`predict` (and of :func:`sensitivity`, ``moved``)."""
    seeds = list(next(iter(runs["circle"].values())))
    lines = ["# The bench twin: calibrated on the circle, the triangle predicted", "",
             "Generated by `python -m scenarios.studies.twin_fit report --docs` (scenarios/studies/twin_fit.py) from the runs of that "
             "call; the method, the choices and a reading: docs/twin_method.md. The twin's scenes are "
             "`bench_real_circle_<S>` and `bench_real_triangle_<S>` (scenarios/scenes/twin.py); the parameters' one "
             "source is scenarios/scenes/bench_twin.toml.", "",
             "## Fitted parameters (circle only: Tables 9, 11, 13)", "",
             "| parameter | value | bounds | meaning |", "|---|---|---|---|"]
    for name, value in twin.values().items():
        b = PARAMETERS[name]
        lines.append(f"| `{name}` | {value:.4g} {b.unit} | [{b.low:g}, {b.high:g}] | {b.meaning} |")
    lines += ["", f"Fit: loss {fit_info.get('loss', math.nan):.4f} (start {fit_info.get('start_loss', math.nan):.4f}), "
                  f"{fit_info.get('evaluations', '?')} evaluations of 8 circle runs × seeds {fit_info.get('seeds')}, "
                  f"{fit_info.get('optimizer', '?')}, {fit_info.get('wall_s', '?')} s wall, commit "
                  f"{fit_info.get('commit', '?')}.", "",
              f"Below, ours = the mean over the {len(seeds)} noise seeds {seeds} (min–max in brackets); "
              "'ratio' = ours / bench.", ""]
    for kind, title in (("circle", "Circle: fitted (Tables 9, 13)"),
                        ("triangle", "Triangle: predicted without refitting (Tables 10, 14)")):
        lines += [f"## {title}", "",
                  "| strategy | e_ef mm twin | e_ef bench | ratio | τ_ef N m twin | τ_ef bench | ratio | "
                  "e_ss mm twin | e_ss bench | settled (of seeds) |", "|---|---|---|---|---|---|---|---|---|---|"]
        for s in ORDER:
            by_seed = runs[kind][s]
            e, el, eh = _spread(by_seed, "e_ef_mm")
            t, tl, th = _spread(by_seed, "tau_ef_Nm")
            ss, sl, sh = _spread(by_seed, "e_ss_mm")
            be, bt, *_rest, bss = THESIS_BENCH[kind][s]
            settled = sum(bool(m["settled"]) for m in by_seed.values())
            lines.append(f"| {s} | {e:.3f} [{el:.3f}–{eh:.3f}] | {be:.2f} | {e / be:.2f} | {t:.3f} [{tl:.3f}–{th:.3f}] | "
                         f"{bt:.3f} | {t / bt:.2f} | {ss:.3f} [{sl:.3f}–{sh:.3f}] | {bss:.3f} | {settled}/{len(by_seed)} |")
        lines += ["", "Adding the sliding-mode term (Tables 11, 12), change of e_ef:", "",
                  "| pair | twin | bench | lower in twin, every seed |", "|---|---|---|---|"]
        for pure, hybrid in PAIRS:
            ours = _spread(runs[kind][hybrid], "e_ef_mm")[0] / _spread(runs[kind][pure], "e_ef_mm")[0] - 1
            every = all(runs[kind][hybrid][seed]["e_ef_mm"] < runs[kind][pure][seed]["e_ef_mm"] for seed in seeds)
            lines.append(f"| {pure} → {hybrid} | {100 * ours:+.1f} % | {THESIS_MD_CHANGE[kind][pure][0]:+.1f} % | "
                         f"{'yes' if every else 'no'} |")
        lines.append("")
    contour = {s: np.mean([m["e_contour_sides_mm"] for m in runs["triangle"][s].values()], axis=0).tolist()
               for s in ORDER}
    lines += side_section(contour, "##", f", twin: mean over the {len(seeds)} seeds")
    if moved:
        lines += [f"## Sensitivity: friction_scale × (1 + step), step in {list(SENSITIVITY_STEPS)}, seed "
                  f"{SPREAD_SEEDS[0]}", "", "min–max over the steps, beside the fitted value:", "",
                  "| strategy | circle e_ef mm | circle e_ss mm | triangle e_ef mm | triangle e_ss mm |",
                  "|---|---|---|---|---|"]
        for s in ORDER:
            cells = []
            for kind in KINDS:
                for key in ("e_ef_mm", "e_ss_mm"):
                    low, high = _spread(moved[kind][s], key)[1:]
                    cells.append(f"{_spread(runs[kind][s], key)[0]:.3f} [{low:.3f}–{high:.3f}]")
            lines.append(f"| {s} | " + " | ".join(cells) + " |")
        lines.append("")
    if spread:
        lines += _render_spread(spread)
    lines += _verdict(runs)
    return "\n".join(lines) + "\n"


def _render_spread(spread: list) -> list:
    lines = [f"## Calibration spread: the ends of the fit's {len(spread)} descents (seed {SPREAD_SEEDS[0]})", "",
             "Each descent of the fit ended at a different point with a nearly equal circle loss; each point's "
             "e_ef / bench, min–max over the points (the fitted twin is the first):", "",
             "| descent end | loss | " + " | ".join(f"`{name}`" for name in PARAMETERS) + " |",
             "|---|---|" + "---|" * len(PARAMETERS)]
    for i, (value, twin, _) in enumerate(sorted(spread, key=lambda item: item[0])):
        lines.append(f"| {i} | {value:.4f} | " + " | ".join(f"{v:.3g}" for v in twin.values().values()) + " |")
    lines += ["", "| strategy | circle e_ef / bench | triangle e_ef / bench |", "|---|---|---|"]
    for s in ORDER:
        cells = []
        for kind in KINDS:
            ratios = [runs[kind][s]["e_ef_mm"] / THESIS_BENCH[kind][s][0] for _, _, runs in spread]
            cells.append(f"{min(ratios):.2f}–{max(ratios):.2f}")
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    return lines + [""]


def _verdict(runs: dict) -> list:
    ratios = {s: _spread(runs["triangle"][s], "e_ef_mm")[0] / THESIS_BENCH["triangle"][s][0] for s in ORDER}
    within30 = [s for s, r in ratios.items() if abs(r - 1) <= 0.30]
    within50 = [s for s, r in ratios.items() if abs(r - 1) <= 0.50]
    md = [_spread(runs["triangle"][h], "e_ef_mm")[0] < _spread(runs["triangle"][p], "e_ef_mm")[0] for p, h in PAIRS]
    return ["## The prediction against the goals", "",
            f"- Predicted triangle e_ef within ±30 % of the bench: {len(within30)} of 8 "
            f"({', '.join(within30) or 'none'}); within ±50 %: {len(within50)} of 8; ratios "
            + ", ".join(f"{s} {r:.2f}" for s, r in ratios.items()) + ".",
            f"- The sliding-mode term lowers the predicted triangle e_ef (seed mean) in {sum(md)} of 4 pairs.", ""]


def plot(runs: dict, path: Path) -> Path:
    """twin.png: e_ef, τ_ef, e_ss of the twin (seed mean, min–max bars) beside the bench."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 2, figsize=(11, 8.5))
    x = np.arange(len(ORDER))
    for col, kind in enumerate(KINDS):
        for row, (key, index, unit) in enumerate((("e_ef_mm", 0, "e_ef [mm]"), ("tau_ef_Nm", 1, "τ_ef [N m]"),
                                                  ("e_ss_mm", 4, "e_ss [mm]"))):
            ax = axes[row, col]
            stats = np.array([_spread(runs[kind][s], key) for s in ORDER])
            ax.bar(x - 0.2, stats[:, 0], 0.4, yerr=np.clip([stats[:, 0] - stats[:, 1], stats[:, 2] - stats[:, 0]], 0.0, None),
                   label="twin (5 seeds)", capsize=2)
            ax.bar(x + 0.2, [THESIS_BENCH[kind][s][index] for s in ORDER], 0.4, label="thesis bench")
            ax.set_xticks(x, ORDER, fontsize=8)
            ax.set_ylabel(unit)
            ax.set_title(f"{kind} ({'fitted' if kind == 'circle' else 'predicted'}): {unit}")
            if key == "e_ss_mm":
                ax.set_yscale("log")
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def write_twin_report(out_dir="out/twin", seeds=SPREAD_SEEDS) -> Path:
    """Run the 16 twin scenes for every seed; write ``twin.md`` (the tables; the method is
    docs/twin_method.md, written by hand, linked), ``twin.png`` and ``twin_runs.json`` (every
    run's metrics) in ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    twin = load_twin()
    runs = predict(twin, seeds)
    moved = sensitivity(twin)
    spread = calibration_spread(read_fit())
    kept = (*METRICS, "settled", "t_settle_s", "e_ss_1s_mm", "completed", "e_contour_sides_mm")
    slim = {kind: {s: {str(seed): {k: m[k] for k in kept if k in m} for seed, m in by_seed.items()}
                   for s, by_seed in by_kind.items()} for kind, by_kind in runs.items()}
    (out / "twin_runs.json").write_text(json.dumps(slim, indent=1) + "\n")
    plot(runs, out / "twin.png")
    text = render(runs, twin, read_fit(), moved, spread) + "![twin beside the bench](twin.png)\n\n" + METHOD_LINK
    path = out / "twin.md"
    path.write_text(text)
    return path


#: The end of the generated docs/twin.md: where the hand-written method is (not a copy of it).
METHOD_LINK = ("The method, the choices (the settled steady-state error, the computation delay, the twin's "
               "parameters) and a reading of these tables: [twin_method.md](twin_method.md).\n")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", nargs="?", choices=("fit", "report", "all"), default="all")
    parser.add_argument("--points", type=int, default=64, help="Sobol points screened (default 64)")
    parser.add_argument("--starts", type=int, default=4, help="descents, from the best screened points (default 4)")
    parser.add_argument("--maxfev", type=int, default=120, help="most evaluations of each descent (default 120)")
    parser.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    parser.add_argument("--out", default="out/twin", help="where twin.md, twin.png go (default out/twin)")
    parser.add_argument("--docs", action="store_true", help="write them into the repository's docs/ instead")
    args = parser.parse_args(argv)
    if args.docs:
        args.out = str(ROOT / "docs")
    if args.what in ("fit", "all"):
        twin = fit(args.points, args.starts, args.maxfev, workers=args.workers)
        print("fitted:", twin.values())
    if args.what in ("report", "all"):
        print(write_twin_report(args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
