"""The wheeled pendulum's trade study and extremes: fidelity switches, sample time, battery voltage.

``python -m scenarios.studies.pendulum_trade [--quick] [--out DIR] [--docs]`` (also ``parcosim trade
pendulum_balance``, :func:`run_pendulum_trade`) measures, each on ``pendulum_balance``
unless said otherwise:

* the fidelity switches (yaw, electrics, friction, the seed's model, the plant's RK4
  substeps): wall time and the RMS deviation of the pitch and the axle position from the
  default scene run with the plant at 32 substeps (the most accurate setting);
* the sample time T (controller, drives and communication step together; the plant keeps
  0.5 ms RK4 steps) up to where the balance is lost;
* the battery voltage down to where the robot no longer recovers from 5 degrees;
* ``pendulum_drive`` with ``model="seed"`` against ``"exact"``: where they differ.

``--docs`` writes the figures docs/pendulum_sweeps.png and docs/pendulum_drive.png.
"""
from __future__ import annotations

import argparse
import csv
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from scenarios.scenes.pendulum import BALANCED_DEG, PendulumFidelity, pendulum_scene
from scenarios.run.runner import atomic_write, error_message, run_scene

SAMPLE_TIMES = (1e-3, 2e-3, 4e-3, 5e-3, 6e-3, 6.5e-3, 7e-3, 7.5e-3, 8e-3, 10e-3, 15e-3, 20e-3)
BATTERY_VOLTAGES = (8.0, 4.0, 2.0, 1.6, 1.5, 1.45, 1.4, 1.35, 1.3, 1.2, 1.0, 0.6)
#: The plant's RK4 step in the sample-time sweep [s].
PLANT_STEP = 0.5e-3
DOCS = Path(__file__).resolve().parents[2] / "docs"


def _with_plant(scene, **parameters):
    components = tuple(replace(c, parameters={**c.parameters, **parameters}) if c.name == "plant" else c
                       for c in scene.system.components)
    return replace(scene, system=replace(scene.system, components=components))


def _short(scene, stop):
    return scene if stop is None else replace(scene, system=replace(scene.system, stop_time=stop),
                                              window=(0.0, stop))


def balanced(metrics: dict) -> bool:
    """Completed and within :data:`BALANCED_DEG` over the last second."""
    return bool(metrics["completed"]) and metrics["last_second_pitch_deg"] <= BALANCED_DEG


def fidelity_rows(name: str = "pendulum_balance", stop: float | None = None) -> list:
    """One row per setting: wall time, metrics, RMS deviation from the 32-substep run."""
    settings = {
        "defaults": pendulum_scene(name),
        "yaw off": pendulum_scene(name, PendulumFidelity(yaw=False)),
        "ideal electrics": pendulum_scene(name, PendulumFidelity(electrics="ideal")),
        "friction off": pendulum_scene(name, PendulumFidelity(friction=False)),
        "seed model": pendulum_scene(name, PendulumFidelity(model="seed")),
        "plant substeps 1": _with_plant(pendulum_scene(name), substeps=1),
        "plant substeps 8": _with_plant(pendulum_scene(name), substeps=8),
    }
    truth = run_scene(_short(_with_plant(pendulum_scene(name), substeps=32), stop)).columns
    rows = []
    for label, scene in settings.items():
        start = time.perf_counter()
        outcome = run_scene(_short(scene, stop))
        wall = time.perf_counter() - start
        c, m = outcome.columns, outcome.metrics
        n = len(c["t"])
        rows.append({"setting": label, "wall_s": wall, "completed": m["completed"],
                     "rms_psi_deg": math.degrees(float(np.sqrt(np.mean((c["psi"] - truth["psi"][:n]) ** 2)))),
                     "rms_axle_mm": 1e3 * float(np.sqrt(np.mean((c["x"] - truth["x"][:n]) ** 2
                                                                + (c["y"] - truth["y"][:n]) ** 2))),
                     "last_second_pitch_deg": m.get("last_second_pitch_deg", float("nan")),
                     "energy_J": m.get("energy_J", float("nan"))})
    return rows


def sample_time_rows(times=SAMPLE_TIMES) -> list:
    """``pendulum_balance`` at each sample time T (the plant at :data:`PLANT_STEP` RK4 steps)."""
    rows = []
    for T in times:
        scene = _with_plant(pendulum_scene("pendulum_balance", sample_time=T), substeps=max(1, round(T / PLANT_STEP)))
        m = run_scene(scene).metrics
        rows.append({"T_ms": 1e3 * T, "balanced": balanced(m), "completed": m["completed"],
                     "peak_pitch_deg": m["peak_pitch_deg"], "last_second_pitch_deg": m["last_second_pitch_deg"],
                     "error": error_message(m)})
    return rows


def battery_rows(voltages=BATTERY_VOLTAGES) -> list:
    """``pendulum_balance`` (release at 5 degrees) at each battery voltage."""
    rows = []
    for v in voltages:
        outcome = run_scene(pendulum_scene("pendulum_balance", v_battery=v))
        m = outcome.metrics
        rows.append({"v_battery": v, "balanced": balanced(m), "completed": m["completed"],
                     "peak_pitch_deg": m["peak_pitch_deg"], "last_second_pitch_deg": m["last_second_pitch_deg"],
                     "peak_voltage": float(np.max(np.abs(outcome.columns["v_l"]))), "error": error_message(m)})
    return rows


def drive_comparison() -> dict:
    """``pendulum_drive`` with the exact and the seed's model: runs and their largest differences."""
    runs = {model: run_scene(pendulum_scene("pendulum_drive", PendulumFidelity(model=model)))
            for model in ("exact", "seed")}
    a, b = runs["exact"].columns, runs["seed"].columns
    gap = np.hypot(a["x"] - b["x"], a["y"] - b["y"])
    turning = (a["t"] >= 6.0) & (a["t"] <= 8.0)
    # Open loop, driving and turning at once: the two terms' share of the accelerations.
    from plant.wheeled import WheeledPendulum

    state = [0.0, math.radians(5.0), 0.0, 0.0, 0.0, 10.0, 0.0, 2.0]   # psi 5 deg, theta' 10, phi' 2 rad/s
    exact, seed = (WheeledPendulum(model=m).derivative(state)[5:] for m in ("exact", "seed"))
    return {"open_loop_acceleration_gap": dict(zip(("ddtheta", "ddpsi", "ddphi"), (exact - seed).tolist())),
            "open_loop_accelerations_exact": dict(zip(("ddtheta", "ddpsi", "ddphi"), exact.tolist())),
            "runs": runs, "max_axle_gap_mm": 1e3 * float(np.max(gap)),
            "max_pitch_gap_deg": math.degrees(float(np.max(np.abs(a["psi"] - b["psi"])))),
            "max_pitch_gap_turning_deg": math.degrees(float(np.max(np.abs(a["psi"] - b["psi"])[turning]))),
            "final_position_error_mm": {m: r.metrics["final_position_error_mm"] for m, r in runs.items()}}


def markdown(rows: list) -> str:
    """A markdown table of ``rows`` (dicts with the same keys)."""
    keys = list(rows[0])
    fmt = lambda v: f"{v:.4g}" if isinstance(v, float) else str(v)   # noqa: E731
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(fmt(r[k]) for k in keys) + " |" for r in rows]
    return "\n".join(lines)


def plot(sample_rows, battery, comparison, directory: Path) -> list:
    """docs figures: the two sweeps, and the drive's path (exact vs seed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    for ax, rows, key, label in ((axes[0], sample_rows, "T_ms", "sample time T [ms]"),
                                 (axes[1], battery, "v_battery", "battery voltage [V]")):
        x = [r[key] for r in rows]
        ax.semilogy(x, [max(r["last_second_pitch_deg"], 1e-4) if r["completed"] else np.nan for r in rows], "o-",
                    label="max |psi|, last second (completed runs)")
        for r in rows:
            if not r["completed"]:
                ax.axvline(r[key], color="C3", lw=0.8, ls=":")
        ax.axhline(BALANCED_DEG, color="k", lw=0.6, ls="--", label=f"{BALANCED_DEG:g} deg")
        ax.set(xlabel=label, ylabel="deg", title="pendulum_balance (red: fell)")
        ax.legend(fontsize=7)
    files = [directory / "pendulum_sweeps.png"]
    fig.tight_layout()
    fig.savefig(files[-1], dpi=110)
    plt.close(fig)
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for model, outcome in comparison["runs"].items():
        c = outcome.columns
        axes[0].plot(c["x"], c["y"], label=model)
        axes[1].plot(c["t"], np.degrees(c["psi"]), lw=0.8, label=model)
    c = comparison["runs"]["exact"].columns
    s = comparison["runs"]["seed"].columns
    axes[0].plot(c["x_d"], c["y_d"], "k--", lw=0.8, label="reference")
    axes[0].set(xlabel="x [m]", ylabel="y [m]", title="pendulum_drive: axle path", aspect="equal", ylim=(-0.3, 0.3))
    axes[1].set(xlabel="t [s]", ylabel="psi [deg]", title="pitch")
    axes[2].plot(c["t"], 1e3 * np.hypot(c["x"] - s["x"], c["y"] - s["y"]), lw=0.8, label="|axle exact - seed|")
    axes[2].set(xlabel="t [s]", ylabel="mm", title="exact vs seed model")
    for ax in axes:
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    files.append(directory / "pendulum_drive.png")
    fig.tight_layout()
    fig.savefig(files[-1], dpi=110)
    plt.close(fig)
    return files


def run_pendulum_trade(scene: str = "pendulum_balance", quick: bool = False, out_dir=None, progress=None) -> dict:
    """The fidelity table of ``scene`` (``quick``: 1 s, no sweeps) and, unless quick, the
    sample-time and battery sweeps; with ``out_dir`` writes trade.csv and trade.md there."""
    say = progress or (lambda line: None)
    say(f"{scene}: fidelity settings ...")
    report = {"fidelity": fidelity_rows(scene, 1.0 if quick else None)}
    if not quick:
        say("sample times ...")
        report["sample_time"] = sample_time_rows()
        say("battery voltages ...")
        report["battery"] = battery_rows()
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        rows = report["fidelity"]

        def write(f):
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)

        atomic_write(out / "trade.csv", write)
        text = "\n\n".join(f"## {part}\n\n{markdown(rows)}" for part, rows in report.items())
        (out / "trade.md").write_text(f"# parcosim trade {scene}{' --quick' if quick else ''}\n\n{text}\n")
    return report


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default="out/pendulum_trade")
    parser.add_argument("--docs", action="store_true", help="write the figures into docs/")
    args = parser.parse_args(argv)
    report = run_pendulum_trade(quick=args.quick, out_dir=args.out, progress=print)
    for part, rows in report.items():
        print(f"\n{part}\n{markdown(rows)}")
    if not args.quick:
        comparison = drive_comparison()
        print({k: v for k, v in comparison.items() if k != "runs"})
        if args.docs:
            print(plot(report["sample_time"], report["battery"], comparison, DOCS))


if __name__ == "__main__":
    main()
