"""The compiled mode against the in-process one on every scene, side by side in one run.

    python benchmarks/compiled_scenes.py                        # every scene of `parcosim list`, full length
    python benchmarks/compiled_scenes.py --scenes bench_circle_TCMDx --drives-in-plant 8

For each scene: ``run_scene(scene, mode="inprocess")`` then ``mode="compiled"``; prints the
largest end-effector path difference between them [m], the relative difference of e_ef, the
steps the compiled loop handed to Python, the compile (or cache-load) time and both real-time
factors, by wall time and by the CPU time of the stepping thread (on a loaded machine compare
within a row; the CPU-time figures are the steadier ones).  With
``--drives-in-plant N`` every scene with drives also runs with them inside the plant.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from scenarios.run.runner import run_scene  # noqa: E402
from scenarios.scenes.catalogue import get_scene, scene_names
from scenarios.scenes.transforms import drives_in_plant  # noqa: E402


def compare(scene) -> dict:
    """In process and compiled runs of ``scene``: their differences and speeds."""
    slow = run_scene(scene, mode="inprocess")
    fast = run_scene(scene, mode="compiled")
    a, b = slow.columns, fast.columns
    n = min(len(a["t"]), len(b["t"]))
    path = float(np.max(np.hypot(a["x"][:n] - b["x"][:n], a["y"][:n] - b["y"][:n]))) if n else math.nan
    e0, e1 = slow.metrics["e_ef_mm"], fast.metrics["e_ef_mm"]
    return {"scene": scene.name, "mode": fast.metrics["mode"], "rows": (len(a["t"]), len(b["t"])),
            "path_m": path, "e_ef_rel": abs(e1 - e0) / abs(e0) if e0 else math.nan,
            "identical": all(np.array_equal(a[k], b[k], equal_nan=True) for k in a),
            "python_steps": fast.metrics.get("python_steps"), "compile_s": fast.metrics.get("compile_s", math.nan),
            "rtf_inprocess": slow.metrics["realtime_factor"], "rtf_compiled": fast.metrics["realtime_factor"],
            "cpu_inprocess": slow.metrics["realtime_factor_cpu"], "cpu_compiled": fast.metrics["realtime_factor_cpu"],
            "error": fast.metrics.get("error"), "same_error": slow.metrics.get("error") == fast.metrics.get("error")}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="*", default=None, help="scene names (default: all)")
    parser.add_argument("--drives-in-plant", type=int, default=None, metavar="N")
    args = parser.parse_args(argv)
    scenes = [get_scene(name) for name in (args.scenes or scene_names())]
    if args.drives_in_plant:
        scenes += [drives_in_plant(s, substeps=args.drives_in_plant) for s in list(scenes)
                   if any(c.model == "DCMotorDrive" for c in s.system.components)]
    print(f"load average before: {'/'.join(f'{v:.2f}' for v in os.getloadavg())}")
    print("| scene | bit-identical | path diff [m] | e_ef rel. diff | steps in Python | compile_s | "
          "RTF in process | RTF compiled | ratio | RTF in process, CPU | RTF compiled, CPU | ratio, CPU |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for scene in scenes:
        r = compare(scene)
        name = scene.name + (" (drives in plant)" if "drives integrated" in scene.description else "")
        print(f"| {name} | {'yes' if r['identical'] else 'no'} | {r['path_m']:.3g} | {r['e_ef_rel']:.3g} | "
              f"{r['python_steps']} | {r['compile_s']:.2f} | {r['rtf_inprocess']:.0f}x | {r['rtf_compiled']:.0f}x | "
              f"{r['rtf_compiled'] / r['rtf_inprocess']:.1f} | {r['cpu_inprocess']:.0f}x | {r['cpu_compiled']:.0f}x | "
              f"{r['cpu_compiled'] / r['cpu_inprocess']:.1f} |", flush=True)
    print(f"load average after: {'/'.join(f'{v:.2f}' for v in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
