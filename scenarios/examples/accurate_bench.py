"""Example: a bench scene with the drives inside the plant, against the monolithic reference.

    python -m scenarios.examples.accurate_bench [SCENE] [--stop-time S] [--substeps N]

Runs the scene twice, as it is (separate drive FMUs) and with
:func:`scenarios.scenes.transforms.drives_in_plant` (one ``ActuatedFiveBarPlant``, RK4 ``substeps`` per
1 ms), compares both with the scene's monolithic reference
(:func:`scenarios.reference.reference_run`), and prints the end-effector deviation, the
samples where an encoder reading differs from the reference's, and the wall time of each.
Copy it and change the scene, the substeps or the plant's ``method``.
"""
from __future__ import annotations

import argparse
from dataclasses import replace

from fmus.cosim.master import simulate
from scenarios.reference import deviation, encoder_differences, reference_run
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m scenarios.examples.accurate_bench", description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default="bench_circle_TCMDx")
    parser.add_argument("--stop-time", type=float, default=2.0)
    parser.add_argument("--substeps", type=int, default=8)
    args = parser.parse_args(argv)

    scene = get_scene(args.scene)
    scene = replace(scene, system=replace(scene.system, stop_time=args.stop_time))
    reference = reference_run(scene)
    print(f"{scene.name}, 0-{args.stop_time:g} s: reference (DOP853, rtol 1e-10) {reference.wall_s:.1f} s")
    record = ("plant.q1_enc", "plant.q2_enc")
    for label, variant in (("separate drives (the scene)", scene),
                           (f"drives in plant, RK4 x{args.substeps}", drives_in_plant(scene, substeps=args.substeps))):
        system = replace(variant.system, record=tuple(dict.fromkeys(variant.system.record + record)))
        result = simulate(system)
        d = deviation(result, reference)
        print(f"  {label:<32s} RMS {d['rms']:.2e} m, max {d['max']:.2e} m, "
              f"{encoder_differences(result, reference)[0]} encoder differences, {result.wall_s:.2f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
