"""Export a scene to SSP, run it in fmpy and Ecos, compare with the master's Jacobi run.

    python benchmarks/ssp_compare.py [SCENE]      (default bench_circle_TCMDx)

Prints, per runner, the number of common communication points, the largest end-effector
difference to ``fmus.cosim.master.simulate(system, mode="fmu", coupling="jacobi")`` and the
wall times.
"""
import sys
import tempfile
from pathlib import Path

import numpy as np

from fmus.cosim.master import simulate
from fmus.ssp.export import export_ssp
from fmus.ssp.run import ecos_available, simulate_ssp_ecos, simulate_ssp_fmpy
from scenarios.scenes.catalogue import get_scene


def main(scene_name="bench_circle_TCMDx"):
    system = get_scene(scene_name).system
    master = simulate(system, mode="fmu", coupling="jacobi")
    print(f"master (jacobi, fmu): {len(master.time)} points, {master.wall_s:.2f} s")
    with tempfile.TemporaryDirectory() as tmp:
        path = export_ssp(system, Path(tmp) / f"{scene_name}.ssp")
        runners = {"fmpy": lambda: simulate_ssp_fmpy(path)}
        if ecos_available() is None:
            runners["ecos"] = lambda: simulate_ssp_ecos(path, ["plant.x", "plant.y"])
        else:
            print(f"ecos: skipped ({ecos_available()})")
        for name, run in runners.items():
            result = run()
            index = {round(t / system.step): i for i, t in enumerate(result.time)}
            common = [k for k in range(len(master.time)) if k in index]
            theirs = [index[k] for k in common]
            diff = max(np.max(np.abs(master[s][common] - result.signals[s][theirs])) for s in ("plant.x", "plant.y"))
            print(f"{name}: {len(common)} common points, max |Δ| end effector {diff:.3g} m, "
                  f"{result.wall_s:.2f} s, error: {result.error}")


if __name__ == "__main__":
    main(*sys.argv[1:])
