"""Full-length regression of 21 scenes against stored metrics: thesis_sim_circle, the thesis' 16
bench scenes and the 4 of seed 001's sliding-mode law (:func:`regression_scenes`).

    python -m scenarios.batch.regression              # compare with tests/data/scene_metrics.json
    python -m scenarios.batch.regression --write      # regenerate it (after a change you mean)
    python -m scenarios.batch.regression --sensitivity   # the spread a 1e-12 m start offset causes

``tests/scenarios/batch/test_regression.py`` runs the comparison in the default suite (21 runs, ~1 min).
The stored file holds, per scene, the metrics of (7.31-7.32) (e_ef, tau_ef), the settled
steady-state error, its settling time and the earlier one-second value (:mod:`scenarios.run.metrics`),
the peak error, and the git commit that wrote them.

Tolerance (:data:`RELATIVE_TOLERANCE`): one machine reproduces every run bit for bit (the
master is deterministic), so the tolerance only has to absorb what another machine's libm,
numpy build or C compiler can change: last-bit differences in sin, cos, sqrt and
sums.  ``--sensitivity`` measures what such differences grow into over a whole run by moving
the start point by 1e-12 m (10^4 times more than a last-bit change of x0): the largest
relative change of a metric over the scenes (docs/testing.md; measured when they were the first 17).  The tolerance is that
spread times 10, and at least 1e-9.
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

from scenarios.run.runner import run_scene
from scenarios.scenes.catalogue import get_scene, scene_names
from scenarios.scenes.twin import twin_scene_names

ROOT = Path(__file__).resolve().parents[2]
STORED = ROOT / "tests" / "data" / "scene_metrics.json"
METRICS = ("e_ef_mm", "tau_ef_Nm", "e_ss_mm", "e_ss_1s_mm", "t_settle_s", "e_max_mm")
#: Relative tolerance of the comparison (module docstring; docs/testing.md).
RELATIVE_TOLERANCE = 1.5e-6
#: The sliding-mode strategy and the one it is added to (7.2.6): the thesis' 8 pairs are
#: these 4 on the circle and the triangle.
MD_PAIRS = (("PDq", "PDMDq"), ("PDx", "PDMDx"), ("TCq", "TCMDq"), ("TCx", "TCMDx"))


def regression_scenes() -> list[str]:
    """thesis_sim_circle and the bench scenes (the thesis' 16 and the 4 of seed 001's SMC law);
    not the bench twin's, whose calibration changes when it is refitted (docs/twin.md)."""
    twin = set(twin_scene_names())
    return ["thesis_sim_circle"] + [n for n in scene_names() if n.startswith("bench_") and n not in twin]


def _start_offset(scene, dx):
    components = tuple(
        replace(c, parameters={**c.parameters, "x0": c.parameters["x0"] + dx}) if "x0" in c.parameters else c
        for c in scene.system.components)
    return replace(scene, system=replace(scene.system, components=components))


def measure(name: str, start_offset: float = 0.0) -> dict:
    """The stored metrics of one full-length in-process run."""
    scene = get_scene(name)
    if start_offset:
        scene = _start_offset(scene, start_offset)
    outcome = run_scene(scene, plots=False)
    if outcome.result.error:
        raise RuntimeError(f"{name}: {outcome.result.error}")
    values = {key: float(outcome.metrics[key]) for key in METRICS}
    return {key: (v if math.isfinite(v) else None) for key, v in values.items()}   # no e_ss: no stop or not settled


def load() -> dict:
    return json.loads(STORED.read_text())


def write():
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    data = {"commit": commit, "scenes": {name: measure(name) for name in regression_scenes()}}
    STORED.parent.mkdir(parents=True, exist_ok=True)
    STORED.write_text(json.dumps(data, indent=1) + "\n")
    return data


def compare() -> list[str]:
    """Lines naming every metric off the stored value by more than the tolerance."""
    stored, problems = load()["scenes"], []
    for name in regression_scenes():
        now = measure(name)
        for key in METRICS:
            a, b = now[key], stored[name][key]
            if a == b:
                continue
            if a is None or b is None or abs(a - b) > RELATIVE_TOLERANCE * abs(b):
                problems.append(f"{name} {key}: {a!r}, stored {b!r}")
    return problems


def sensitivity(dx: float = 1e-12) -> float:
    """Largest relative change of a stored metric when every start point moves by dx."""
    stored, worst = load()["scenes"], 0.0
    for name in regression_scenes():
        moved = measure(name, dx)
        for key in METRICS:
            if stored[name][key]:
                change = abs(moved[key] - stored[name][key]) / abs(stored[name][key])
                print(f"{name:24s} {key:10s} {change:.2e}", flush=True)
                worst = max(worst, change)
    return worst


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true")
    parser.add_argument("--sensitivity", action="store_true")
    args = parser.parse_args(argv)
    if args.write:
        for name, metrics in write()["scenes"].items():
            print(name, metrics)
        return 0
    if args.sensitivity:
        print(f"largest relative change: {sensitivity():.2e}")
        return 0
    problems = compare()
    print("\n".join(problems) or f"all {len(regression_scenes())} scenes match")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
