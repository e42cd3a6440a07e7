"""Plant accuracy against the independent reference, per integrator setting.

Prints the markdown table of docs/plant.md: maximum end-effector deviation over
0.4 s from ``tests/support/lagrange5r.py`` (torques held per 1 ms step), for a
gentle and a fast torque profile, and the loop-closure residual.

    python benchmarks/plant_accuracy.py
"""
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from plant import ACCURATE, IntegratorSettings, PlantError, PlantSimulator, get_preset  # noqa: E402
from tests.plant.test_plant_dynamics import held_reference  # noqa: E402

CASES = (("thesis_sim", 0.07, 0.17), ("bench", -0.002, 0.108))
SETTINGS = {
    "rk4, 1 substep (default)": IntegratorSettings(),
    "rk4, 2 substeps": IntegratorSettings(substeps=2),
    "rk4, 4 substeps": IntegratorSettings(substeps=4),
    "rk4, projection on": IntegratorSettings(project=True),
    "rk4, baumgarte 0": IntegratorSettings(baumgarte=0.0),
    "rk4, baumgarte 100": IntegratorSettings(baumgarte=100.0),
    "dopri5, rtol 1e-10": IntegratorSettings(method="dopri5"),
    "dopri5, rtol 1e-12 (ACCURATE)": ACCURATE,
}


def profile(amplitude):
    return lambda t: (amplitude * math.sin(5 * math.pi * t) + amplitude / 3, -amplitude * math.cos(3 * math.pi * t))


def deviation(preset, x0, y0, settings, tau, expected):
    sim = PlantSimulator(get_preset(preset), x0, y0, settings)
    err = res = 0.0
    try:
        for k, (x, y) in enumerate(expected):
            sim.step(*tau(k * 1e-3), 1e-3)
            out = sim.outputs()
            err = max(err, math.hypot(out["x"] - x, out["y"] - y))
            res = max(res, out["residual"])
    except PlantError as exc:
        return f"fails: {str(exc)[:40]}"
    return f"{err:.1e} m ({res:.0e})"


def main():
    profiles = {"0.06 N m": profile(0.06), "0.12 N m": profile(0.12)}
    refs = {(c, p): held_reference(*c, tau)[:, :2] for c in CASES for p, tau in profiles.items()}
    head = [f"{c[0]} {p}" for c in CASES for p in profiles]
    print("| settings | " + " | ".join(head) + " | µs/step |")
    print("|---" * (len(head) + 2) + "|")
    PlantSimulator(get_preset("bench"), 0.0, 0.17).step(0.0, 0.0, 1e-3)   # compile the kernel first
    for name, settings in SETTINGS.items():
        start = time.perf_counter()
        cells = [deviation(*c, settings, profiles[p], refs[(c, p)]) for c in CASES for p in profiles]
        us = (time.perf_counter() - start) / (400 * len(cells)) * 1e6
        print(f"| {name} | " + " | ".join(cells) + f" | {us:.0f} |")


if __name__ == "__main__":
    main()
