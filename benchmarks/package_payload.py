"""The package's chain against a plant unlike its model: a payload the model does not have.

    python benchmarks/package_payload.py [--gains 0,0.1,0.3,1] [--stop-time 2] [--drives-in-plant N]

For three bench scenes and payloads of 0, 40 and 100 g on the real plant only, the package
is run as a Jacobi master runs it (``scenarios.packaging.chain.run_jacobi``, fmpy's zeros on the
first step) and its RMS end-effector error over [1, stop] s is divided by our master's
with the same loaded plant (whose controller does not know the payload either).  One row
per speed gain of the measurement correction (``plant.correction.VELOCITY_GAIN``): it acts
where the chain measures no speed, i.e. with ``--drives-in-plant N`` (the bench package
measures the shaft speeds for its drives, and takes them as they are).
Figures in docs/ssp.md.
"""
from __future__ import annotations

import argparse
import dataclasses

import plant.correction as correction
from fmus.cosim.master import simulate
from scenarios.run.metrics import rms_norm
from scenarios.packaging.chain import package_scene, run_jacobi
from scenarios.scenes.thesis import Fidelity, bench
from scenarios.scenes.transforms import drives_in_plant

CASES = (("TCMDx", "circle"), ("PDq", "circle"), ("TCMDq", "triangle"))
PAYLOADS = (0.0, 0.04, 0.1)


def _short(scene, stop):
    return dataclasses.replace(scene, system=dataclasses.replace(scene.system, stop_time=stop))


def _tracking(time, x, y, x_d, y_d, stop):
    w = (time >= 1.0 - 1e-9) & (time <= stop + 1e-9)
    return rms_norm(x_d[w] - x[w], y_d[w] - y[w])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gains", default="0,0.1,0.3,1")
    parser.add_argument("--stop-time", type=float, default=2.0)
    parser.add_argument("--drives-in-plant", type=int, default=None, metavar="N")
    args = parser.parse_args()
    stop = args.stop_time

    def scene(strategy, kind, m0=0.0):
        s = _short(bench(strategy, kind, fidelity=Fidelity(m0=m0)), stop)
        return s if args.drives_in_plant is None else drives_in_plant(s, substeps=args.drives_in_plant)

    masters = {}
    for strategy, kind in CASES:
        for m0 in PAYLOADS:
            r = simulate(scene(strategy, kind, m0).system)
            masters[strategy, kind, m0] = _tracking(r.time, r["plant.x"], r["plant.y"], r["traj.x_d"],
                                                    r["traj.y_d"], stop)
    print("gain | " + " | ".join(f"{s} {k} {1000 * m:.0f} g" for s, k in CASES for m in PAYLOADS) + " | range")
    for gain in (float(g) for g in args.gains.split(",")):
        correction.VELOCITY_GAIN = gain
        ratios, cells = [], []
        for strategy, kind in CASES:
            package = package_scene(scene(strategy, kind))
            for m0 in PAYLOADS:
                run = run_jacobi(package, {"m0": m0}, zero_first_inputs=True)
                ratio = _tracking(run.time, run.x, run.y, run.x_d, run.y_d, stop) / masters[strategy, kind, m0]
                ratios.append(ratio)
                cells.append(f"{ratio:.4f} ({run.chain.corrections})")
        print(f"{gain:g} | " + " | ".join(cells) + f" | {min(ratios):.3f}-{max(ratios):.3f}")


if __name__ == "__main__":
    main()
