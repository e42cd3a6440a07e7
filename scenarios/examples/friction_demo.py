"""The LuGre model's published behaviours on the paper's example, and the figure of docs/friction.md.

    python -m scenarios.examples.friction_demo [--out out/friction_lugre.png | --docs]

Canudas de Wit et al. (IEEE TAC 1995): a 1 kg mass, σ0 = 1e5 N/m, σ1 = √1e5 N s/m,
σ2 = 0.4 N s/m, Fc = 1 N, Fs = 1.5 N, vs = 0.001 m/s (:data:`PAPER`), stepped the way a drive
steps :mod:`motor.friction`: the speed held over each step, the bristles solved exactly, the
mass integrated with the step's mean friction (:func:`push`: ``pc_lugre_push`` of
kernels/src/drive.c).  Three panels: presliding (a
force below Fc: an elastic displacement ~ F/σ0 with hysteresis), break-away under ramped forces
(near Fs when slow, lower when fast), and a spring (k = 2 N/m) pulled at 0.1 m/s (stick-slip)
and at 0.5 m/s (steady sliding).  tests/motor/test_friction.py checks the same runs against scipy.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import kernels
from motor import friction, kernel

#: The paper's example (translational: N, m, s).
PAPER = {"Fc": 1.0, "Fs": 1.5, "omega_s": 1e-3, "sigma0": 1e5, "sigma1": math.sqrt(1e5), "sigma2": 0.4}
#: Force laws of :func:`push`.
RAMP, SINE, SPRING = 0, 1, 2


def push(kind: int, a: float, b: float, t_end: float, h: float = 1e-5, mass: float = 1.0, model=None):
    """(rows of x, v, z after each step, times): a mass on LuGre friction (:data:`PAPER` by
    default) under the force ``a t`` (:data:`RAMP`), ``a sin(b t)`` (:data:`SINE`) or a spring
    of stiffness ``a`` whose end moves at ``b`` (:data:`SPRING`), from rest, step h [s]."""
    model = friction.LuGre(**PAPER) if model is None else model
    n = int(round(t_end / h))
    rows = np.empty((n, 3))
    kernel.lugre_push(kernels.address(friction.new_lugre(model)), kind, a, b, mass, h, n, kernels.address(rows))
    return rows, (np.arange(n) + 1) * h


def plot(out: Path) -> Path:
    """The three panels, written to ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    rows, t = push(SINE, 0.9, math.pi, 2.0)
    force = 0.9 * np.sin(math.pi * t)
    axes[0].plot(1e6 * rows[:, 0], force)
    axes[0].set(xlabel="displacement [µm]", ylabel="applied force [N]",
                title="presliding: 0.9 sin(πt) N < Fc (hysteresis)")
    for rate in (0.1, 1.0, 10.0):
        rows, t = push(RAMP, rate, 0.0, 2.0 / rate)
        k = int(np.argmax(rows[:, 1] > PAPER["omega_s"]))
        axes[1].plot(1e6 * rows[:, 0], rate * t, label=f"{rate:g} N/s: breaks away at {rate * t[k]:.3f} N")
        axes[1].plot(1e6 * rows[k, 0], rate * t[k], "k.")
    axes[1].axhline(PAPER["Fs"], color="grey", ls=":")
    axes[1].set(xlabel="displacement [µm]", ylabel="applied force [N]", xlim=(0, 200), ylim=(0, 2),
                title="break-away under a ramped force (v > vs)")
    axes[1].legend(fontsize=8)
    for pull in (0.1, 0.5):
        rows, t = push(SPRING, 2.0, pull, 20.0)
        axes[2].plot(t[::100], rows[::100, 1], label=f"spring end at {pull:g} m/s")
    axes[2].set(xlabel="t [s]", ylabel="mass speed [m/s]", title="spring-mass (k = 2 N/m): stick-slip, sliding")
    axes[2].legend(fontsize=8)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description="LuGre friction: the paper's behaviours (figure)")
    parser.add_argument("--out", default="out/friction_lugre.png", help="PNG path (default out/friction_lugre.png)")
    parser.add_argument("--docs", action="store_true", help="write docs/friction_lugre.png instead")
    args = parser.parse_args(argv)
    print(plot(Path(__file__).resolve().parents[2] / "docs" / "friction_lugre.png" if args.docs else Path(args.out)))


if __name__ == "__main__":
    main()
