"""When do counter-masses pay?  The vertical bench with and without them, over circle speeds.

Seed 001's counter-masses (:meth:`plant.presets.ChainParams.counter_offsets`) remove the
gravity load of a vertical 5R but add inertia.  This script runs
:func:`scenarios.scenes.thesis.vertical_circle` with and without them for the circle (7.23) at
several speeds and reports, over the metric window (turns 2 to 8, the steady state): e_ef,
tau_ef (7.31-7.32), the peak torques, the drives' RMS and peak currents and peak voltages,
and the fraction of samples the drives saturate at the supply; the start (2 mm off the
circle) and the sudden stop are outside the window and reported as the run's overall peak
current.  Figures in docs/balanced.md::

    python -m scenarios.studies.balancing [--strategies TCMDx TCx] [--frequencies 0.25 0.5 1 2]
                                  [--out DIR | --docs]     # default out/balancing
    python -m scenarios.studies.balancing --scenes      # the 20 vertical scenes at 1 Hz, a markdown table

writes ``balanced_speeds.csv``, ``balanced_speeds.png`` (tau_ef and RMS current against the
circle's frequency) and ``balanced_circle.png`` (the 1 Hz scenes: path, torques, currents).
"""
from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import numpy as np

from motor import get_motor_preset

from scenarios.run.metrics import in_window
from scenarios.run.runner import run_scene
from controller.strategies import ALL_STRATEGY_NAMES

from scenarios.scenes.thesis import VERTICAL_COUNTER_MASSES, vertical_circle

DEFAULT_FREQUENCIES = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0)
DEFAULT_STRATEGIES = ("TCMDx",)
#: The bench's driver: 12 A continuous, 30 A peak; supply 24 V (the brief ../shared/spec/SYSTEM.md §3).
CONTINUOUS_A, PEAK_A = 12.0, 30.0
COLUMNS = ("strategy", "frequency_Hz", "balanced", "e_ef_mm", "tau_ef_Nm", "tau1_peak_Nm", "tau2_peak_Nm",
           "i1_rms_A", "i2_rms_A", "i_peak_A", "v_peak_V", "saturated_pct", "i_peak_run_A", "error")


def measure(strategy: str, frequency: float, balanced: bool):
    """One run: (row of :data:`COLUMNS`, the run's columns)."""
    outcome = run_scene(vertical_circle(strategy, balanced, frequency=frequency))
    c, m = outcome.columns, outcome.metrics
    w = in_window(c["t"], outcome.scene.window)
    v_max = get_motor_preset("motor1").v_max
    volts = np.maximum(np.abs(c["v1"][w]), np.abs(c["v2"][w]))
    row = {
        "strategy": strategy, "frequency_Hz": frequency, "balanced": balanced,
        "e_ef_mm": m["e_ef_mm"], "tau_ef_Nm": m["tau_ef_Nm"],
        "tau1_peak_Nm": float(np.max(np.abs(c["tau1"][w]))), "tau2_peak_Nm": float(np.max(np.abs(c["tau2"][w]))),
        "i1_rms_A": float(np.sqrt(np.mean(c["i1"][w] ** 2))), "i2_rms_A": float(np.sqrt(np.mean(c["i2"][w] ** 2))),
        "i_peak_A": float(max(np.max(np.abs(c["i1"][w])), np.max(np.abs(c["i2"][w])))),
        "v_peak_V": float(np.max(volts)),
        "saturated_pct": float(100.0 * np.mean(volts >= v_max * (1 - 1e-9))),
        "i_peak_run_A": float(max(np.max(np.abs(c["i1"])), np.max(np.abs(c["i2"])))),
        "error": str(outcome.result.error or ""),
    }
    return row, c


def sweep(strategies=DEFAULT_STRATEGIES, frequencies=DEFAULT_FREQUENCIES, progress=print):
    """Rows of :data:`COLUMNS`, balanced and not, for every strategy and frequency."""
    rows = []
    for strategy in strategies:
        for frequency in frequencies:
            for balanced in (False, True):
                row, _ = measure(strategy, frequency, balanced)
                rows.append(row)
                if progress:
                    progress(f"{strategy} {frequency:g} Hz {'balanced' if balanced else 'plain   '}: "
                             f"e_ef {row['e_ef_mm']:.3f} mm, tau_ef {row['tau_ef_Nm']:.3f} N m, "
                             f"i_rms {max(row['i1_rms_A'], row['i2_rms_A']):.2f} A, "
                             f"saturated {row['saturated_pct']:.1f} %")
    return rows


def break_even(rows, strategy: str, key: str = "tau_ef_Nm"):
    """The first frequency [Hz] where balanced ``key`` goes from at most plain's to above it or
    back (linear between the sweep's points: a point where they are equal is the crossing when
    the gap is positive on its other side), or None when it never does."""
    plain = sorted((r["frequency_Hz"], r[key]) for r in rows if r["strategy"] == strategy and not r["balanced"])
    heavy = dict((r["frequency_Hz"], r[key]) for r in rows if r["strategy"] == strategy and r["balanced"])
    gaps = [(f, heavy[f] - value) for f, value in plain]
    for (f0, g0), (f1, g1) in zip(gaps, gaps[1:]):
        if g0 <= 0.0 < g1 or g1 <= 0.0 < g0:
            return f0 + (f1 - f0) * g0 / (g0 - g1)
    return None


def write_csv(rows, path: Path) -> None:
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})


def plot_sweep(rows, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for strategy in dict.fromkeys(r["strategy"] for r in rows):
        for balanced, style in ((False, "o-"), (True, "s--")):
            sel = [r for r in rows if r["strategy"] == strategy and r["balanced"] == balanced]
            f = [r["frequency_Hz"] for r in sel]
            label = f"{strategy} {'balanced' if balanced else 'plain'}"
            axes[0].plot(f, [r["tau_ef_Nm"] for r in sel], style, label=label)
            axes[1].plot(f, [max(r["i1_rms_A"], r["i2_rms_A"]) for r in sel], style, label=label)
            axes[2].plot(f, [r["e_ef_mm"] for r in sel], style, label=label)
    axes[1].axhline(CONTINUOUS_A, color="k", lw=0.8, ls=":", label="driver continuous 12 A")
    for ax, title in zip(axes, ("tau_ef [N m]", "RMS current, worse drive [A]", "e_ef [mm]")):
        ax.set_xlabel("circle frequency [Hz]")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[1].legend(fontsize=8)
    fig.suptitle(f"Vertical bench, circle (7.23): counter-masses {VERTICAL_COUNTER_MASSES} kg or none")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_circle(strategy: str, path: Path) -> None:
    """The 1 Hz scenes without and with counter-masses: path, torques, currents."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for balanced, color in ((False, "C0"), (True, "C1")):
        _, c = measure(strategy, 1.0, balanced)
        label = "balanced" if balanced else "plain"
        axes[0].plot(1e3 * c["x"], 1e3 * c["y"], color=color, lw=0.8, label=label)
        for j, ls in (("1", "-"), ("2", ":")):
            axes[1].plot(c["t"], c[f"tau{j}"], color=color, ls=ls, lw=0.7, label=f"{label} tau{j}")
            axes[2].plot(c["t"], c[f"i{j}"], color=color, ls=ls, lw=0.7, label=f"{label} i{j}")
    axes[0].plot(1e3 * c["x_d"], 1e3 * c["y_d"], "k--", lw=0.6, label="reference")
    axes[0].set_aspect("equal")
    axes[0].set_xlabel("x [mm]")
    axes[0].set_ylabel("y [mm]")
    axes[1].set_ylabel("torque command [N m]")
    axes[2].set_ylabel("drive current [A]")
    for ax in axes[1:]:
        ax.set_xlabel("t [s]")
        ax.set_ylim(-1.0, 1.0) if ax is axes[1] else ax.set_ylim(-15, 15)
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"vertical_circle_{strategy} and vertical_circle_balanced_{strategy}")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def scene_table(strategies=ALL_STRATEGY_NAMES) -> str:
    """The scenes ``vertical_circle_<S>`` and ``vertical_circle_balanced_<S>`` as a markdown table."""
    lines = ["| strategy | counter-masses | e_ef mm | tau_ef N m | peak tau1, tau2 N m | RMS i1, i2 A "
             "| peak i A (window / run) | peak v V |", "|---|---|---|---|---|---|---|---|"]
    for strategy in strategies:
        for balanced in (False, True):
            r, _ = measure(strategy, 1.0, balanced)
            lines.append(f"| {strategy} | {'yes' if balanced else 'no'} | {r['e_ef_mm']:.3f} | {r['tau_ef_Nm']:.3f} "
                         f"| {r['tau1_peak_Nm']:.2f}, {r['tau2_peak_Nm']:.2f} | {r['i1_rms_A']:.2f}, {r['i2_rms_A']:.2f} "
                         f"| {r['i_peak_A']:.1f} / {r['i_peak_run_A']:.1f} | {r['v_peak_V']:.1f} |"
                         + (f" {r['error']}" if r["error"] else ""))
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--strategies", nargs="+", default=list(DEFAULT_STRATEGIES))
    parser.add_argument("--frequencies", nargs="+", type=float, default=list(DEFAULT_FREQUENCIES))
    parser.add_argument("--out", default="out/balancing", help="where the csv and figures go (default out/balancing)")
    parser.add_argument("--docs", action="store_true", help="write them into the repository's docs/ instead")
    parser.add_argument("--scenes", action="store_true", help="print the 1 Hz scenes' table and stop")
    args = parser.parse_args(argv)
    if args.scenes:
        print(scene_table())
        return 0
    out = Path(__file__).resolve().parents[2] / "docs" if args.docs else Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = sweep(args.strategies, args.frequencies)
    write_csv(rows, out / "balanced_speeds.csv")
    plot_sweep(rows, out / "balanced_speeds.png")
    plot_circle(args.strategies[0], out / "balanced_circle.png")
    for strategy in args.strategies:
        for key in ("tau_ef_Nm", "i1_rms_A", "e_ef_mm"):
            f = break_even(rows, strategy, key)
            print(f"{strategy}: balanced and plain {key} cross at "
                  f"{'no frequency in the sweep' if f is None else f'{f:.3g} Hz'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
