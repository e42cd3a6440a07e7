"""The bench twin's stability margin against the thesis' statement about the bench's.

    python -m scenarios.studies.twin_margin [--kind circle] [--extra 5] [--delays 1 3 6 10 14] [--fc-vel 100]

or in Python: ``margin(kind, extra, delays, fc_vel=...)``.

Section 7.2.12 of the thesis: "um aumento de 5 rad/s nos valores utilizados do parâmetro λ já
seria o suficiente para comprometer a estabilidade do sistema em todas as estratégias de
controle utilizadas" (raising λ of Tables 6-8 by 5 rad/s was found, on the bench, to
compromise stability with every strategy).  This script runs each twin scene with its
table's λ and with λ + ``extra``, for each computation delay in ``delays`` (the twin's is 1
sample) and the derivator's velocity cut-off ``fc_vel`` (the thesis gives none; ours is
100 Hz, docs/derivators.md), in compiled mode, and prints e_ef, τ_ef, e_max and the peak
drive voltage of both: a twin with the bench's margin would degrade at λ + 5; one that tracks
better there has a wider margin than the bench.
Figures: docs/twin_method.md ("Stability margin").
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace

import numpy as np

from controller.strategies import get_strategy

from scenarios.reference import with_parameters as with_system_parameters
from scenarios.run.runner import run_scene
from scenarios.scenes.twin import DELAY_STEPS, KINDS, Twin, bench_real, load_twin
from scenarios.studies.twin_fit import ORDER

#: The thesis' λ step that compromised the bench's stability with every strategy [rad/s].
THESIS_LAMBDA_STEP = 5.0


def with_parameters(scene, name: str, **parameters):
    """``scene`` with component ``name``'s parameters updated by ``parameters``
    (:func:`scenarios.reference.with_parameters` on its system)."""
    return replace(scene, system=with_system_parameters(scene.system, name, **parameters))


def with_controller(scene, **parameters):
    """``scene`` with the controller's parameters updated by ``parameters``."""
    return with_parameters(scene, "ctrl", **parameters)


def margin(kind: str = "circle", extra: float = THESIS_LAMBDA_STEP, delays=(DELAY_STEPS,),
           twin: Twin | None = None, strategies=ORDER, fc_vel: float | None = None) -> list[dict]:
    """One row per (delay, strategy): the metrics of the twin scene at the table's λ
    (``base``) and at λ + ``extra`` (``raised``), compiled mode, seed of the scenes;
    ``fc_vel`` [Hz], if given, is the derivator's velocity cut-off."""
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r}; valid: {', '.join(KINDS)}")
    twin = load_twin() if twin is None else twin
    rows = []
    for delay in delays:
        for s in strategies:
            lam = get_strategy(s, kind).lam
            scene = bench_real(s, kind, twin)
            if fc_vel is not None:
                scene = with_parameters(scene, "deriv", fc_vel=float(fc_vel))
            runs = {label: _run(with_controller(scene, lam=lam + step, delay_steps=int(delay)))
                    for label, step in (("base", 0.0), ("raised", extra))}
            rows.append({"delay": int(delay), "strategy": s, "lam": lam, **runs})
    return rows


def _run(scene) -> dict:
    """The scene's metrics, plus ``v_peak``: the largest drive voltage magnitude of the run [V]
    (the circle's abrupt start asks the most of the drives, 7.2.12)."""
    outcome = run_scene(scene, mode="compiled", plots=False)
    signals = outcome.result.signals
    peak = max(float(np.max(np.abs(signals[f"drive{j}.v"]))) for j in (1, 2))
    return {**outcome.metrics, "v_peak": peak}


def render(rows: list[dict], extra: float) -> str:
    """The rows as a markdown table (e_ef, τ_ef, e_max at λ and at λ + extra)."""
    lines = [f"| delay [samples] | strategy | λ | e_ef mm at λ | at λ+{extra:g} | τ_ef N m at λ | at λ+{extra:g} | "
             f"e_max mm at λ | at λ+{extra:g} | peak drive V at λ | at λ+{extra:g} |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        b, h = r["base"], r["raised"]
        lines.append(f"| {r['delay']} | {r['strategy']} | {r['lam']:g} | {b['e_ef_mm']:.2f} | {h['e_ef_mm']:.2f} | "
                     f"{b['tau_ef_Nm']:.3f} | {h['tau_ef_Nm']:.3f} | {b['e_max_mm']:.1f} | {h['e_max_mm']:.1f} | "
                     f"{b['v_peak']:.1f} | {h['v_peak']:.1f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", default="circle", choices=KINDS)
    parser.add_argument("--extra", type=float, default=THESIS_LAMBDA_STEP, help="λ step [rad/s] (default 5)")
    parser.add_argument("--delays", type=int, nargs="+", default=[DELAY_STEPS],
                        help=f"computation delays [samples] (default {DELAY_STEPS}, the twin's)")
    parser.add_argument("--fc-vel", type=float, default=None,
                        help="the derivator's velocity cut-off [Hz] (default: the scene's, 100)")
    args = parser.parse_args(argv)
    print(render(margin(args.kind, args.extra, args.delays, fc_vel=args.fc_vel), args.extra), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
