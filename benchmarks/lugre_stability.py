"""Where the LuGre drive's 1 ms coupling to an inertia goes unstable (docs/friction.md).

    python benchmarks/lugre_stability.py            # the map on one inertia, then bench scenes
    python benchmarks/lugre_stability.py --no-scenes
    python benchmarks/lugre_stability.py --effect   # the 16 bench scenes, tanh vs LuGre friction

**The map.** A ``motor.Drive`` with ``friction="lugre"`` and ``torque_output="mean"`` (as in
the bench scenes), its current loop holding i = 0, drives a rigid inertia J the way the master
couples them (Gauss-Seidel, the drive first): the drive steps with the speed at t held, the
inertia then integrates the drive's torque held over [t, t + h], exactly.  Started at rest
with a 0.01 rad/s kick, a stable coupling comes to rest in the bristles; an unstable one grows
into a limit cycle.  Reported: the RMS speed over the last 0.5 s of 2 s, relative to the kick
(stable: < 1e-2, decaying).  Beside it the band the linearised presliding loop predicts (z = σ0 held-step
algebra, docs/friction.md): stable iff σ0 h / 2 < σ1 < 2 J / h.

**The scenes.** ``bench_circle_<S>`` with ``Fidelity(friction="lugre")`` and the drives' σ0, σ1
set by ``drive_parameters``: e_ef and whether the run completed.
"""
from __future__ import annotations

import argparse
import math

import numpy as np

from motor import Drive, motor1

H = 1e-3


def coupled_rms(J, sigma0, sigma1, kick=0.01, seconds=2.0):
    """RMS speed over the last 0.5 s of the drive + inertia loop, relative to ``kick``."""
    drive = Drive(motor1.with_(sigma0=sigma0, sigma1=sigma1), friction="lugre", torque_output="mean")
    omega, steps = kick, int(round(seconds / H))
    tail = []
    for k in range(steps):
        tau, _, i = drive.step(0.0, 0.0, omega, drive.i, H)
        omega += H * tau / J
        if not math.isfinite(omega) or abs(omega) > 1e6:
            return math.inf
        if k >= steps - int(0.5 / H):
            tail.append(omega)
    return float(np.sqrt(np.mean(np.square(tail)))) / kick


def predicted_stable(J, sigma0, sigma1):
    """The linearised presliding loop's band: σ0 h / 2 < σ1 < 2 J / h."""
    return sigma0 * H / 2 < sigma1 < 2.0 * J / H


def stability_map(inertias=(motor1.J_rotor, 3e-4, 1e-3), sigma0s=(10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0),
                  sigma1s=(0.0, 0.01, 0.03, 0.1, 0.15, 0.3, 0.5, 1.0)):
    """Rows (J, σ0, σ1, relative RMS, measured stable, predicted stable)."""
    rows = []
    for J in inertias:
        for s0 in sigma0s:
            for s1 in sigma1s:
                rms = coupled_rms(J, s0, s1)
                rows.append((J, s0, s1, rms, rms < 1e-2, predicted_stable(J, s0, s1)))
    return rows


def scene_rows(strategies=("PDq", "TCMDq"), pairs=((100.0, 0.15), (100.0, 0.02), (1000.0, 0.15), (100.0, 0.6))):
    """Rows (strategy, σ0, σ1, e_ef_mm, e_ss_mm, chatter, completed) of the circle scenes with
    LuGre drives; chatter: the RMS step-to-step change of drive 1's shaft torque over the last
    0.5 s (at rest after the stop) [N m]."""
    from scenarios.run.runner import run_scene
    from scenarios.scenes.thesis import Fidelity, bench

    rows = []
    for s in strategies:
        for s0, s1 in pairs:
            f = Fidelity(friction="lugre", drive_parameters=(("sigma0", s0), ("sigma1", s1)))
            o = run_scene(bench(s, "circle", fidelity=f), mode="compiled", plots=False)
            m, t = o.metrics, np.asarray(o.columns["t"])
            tau = np.asarray(o.columns["tau1_shaft"])[t > t[-1] - 0.5]
            chatter = float(np.sqrt(np.mean(np.diff(tau) ** 2)))
            rows.append((s, s0, s1, m["e_ef_mm"], m["e_ss_mm"], chatter, m["completed"] and "error" not in m))
    return rows


def effect_rows():
    """Rows (scene, metrics with tanh friction, metrics with LuGre) of the 16 bench scenes."""
    from controller.strategies import STRATEGY_NAMES
    from scenarios.run.runner import run_scene
    from scenarios.scenes.thesis import Fidelity, bench

    rows = []
    for kind in ("circle", "triangle"):
        for s in STRATEGY_NAMES:
            pair = [run_scene(bench(s, kind, fidelity=Fidelity(friction=f)), mode="compiled", plots=False).metrics
                    for f in ("tanh", "lugre")]
            rows.append((f"bench_{kind}_{s}", *pair))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--no-scenes", action="store_true", help="only the one-inertia map")
    parser.add_argument("--effect", action="store_true", help="only the 16 bench scenes, tanh vs LuGre")
    args = parser.parse_args(argv)
    if args.effect:
        print("| scene | e_ef mm tanh | e_ef mm LuGre | tau_ef N m tanh | tau_ef N m LuGre | e_ss mm tanh | e_ss mm LuGre |")
        print("|---|---|---|---|---|---|---|")
        for name, a, b in effect_rows():
            print(f"| {name} | {a['e_ef_mm']:.3f} | {b['e_ef_mm']:.3f} | {a['tau_ef_Nm']:.4f} | {b['tau_ef_Nm']:.4f} "
                  f"| {a['e_ss_mm']:.3f} | {b['e_ss_mm']:.3f} |")
        return
    rows = stability_map()
    print("| J [kg m2] | sigma0 [N m/rad] | sigma1 [N m s/rad] | RMS / kick | stable | predicted |")
    print("|---|---|---|---|---|---|")
    for J, s0, s1, rms, stable, predicted in rows:
        print(f"| {J:.3g} | {s0:g} | {s1:g} | {rms:.2g} | {'yes' if stable else 'NO'} | {'yes' if predicted else 'no'} |")
    agree = sum(stable == predicted for *_, stable, predicted in rows)
    print(f"\nmeasured == predicted in {agree} of {len(rows)} cases")
    if not args.no_scenes:
        print("\n| strategy | sigma0 | sigma1 | e_ef mm | e_ss mm | torque chatter at rest [N m] | completed |")
        print("|---|---|---|---|---|---|---|")
        for s, s0, s1, e, ess, chatter, ok in scene_rows():
            print(f"| {s} | {s0:g} | {s1:g} | {e:.4g} | {ess:.3g} | {chatter:.2g} | {ok} |")


if __name__ == "__main__":
    main()
