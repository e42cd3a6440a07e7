"""Every recorded signal of every scene, saved and compared: did a change move any result?

    python benchmarks/scene_signals.py dump OUT.npz        # run every scene in process
    python benchmarks/scene_signals.py compare A.npz B.npz # bit-identical signals? largest differences

Run ``dump`` at two commits (e.g. ``git archive`` one into a directory and run there with
``PYTHONPATH`` pointing to it), then ``compare``.
"""
from __future__ import annotations

import sys

import numpy as np


def dump(path: str) -> None:
    from scenarios.run.runner import run_scene
    from scenarios.scenes.catalogue import scene_names

    arrays = {}
    for name in scene_names():
        outcome = run_scene(name, plots=False)
        for signal, values in outcome.result.signals.items():
            arrays[f"{name}|{signal}"] = values
        print(name, {k: outcome.metrics[k] for k in ("e_ef_mm", "tau_ef_Nm", "e_ss_mm")}, flush=True)
    np.savez(path, **arrays)


def compare(a_path: str, b_path: str) -> int:
    a, b = np.load(a_path), np.load(b_path)
    missing = sorted(set(a.files) ^ set(b.files))
    differing = [k for k in sorted(set(a.files) & set(b.files))
                 if a[k].shape != b[k].shape or not np.array_equal(a[k], b[k], equal_nan=True)]
    print(f"{len(a.files)} and {len(b.files)} signals; only in one: {len(missing)}; different: {len(differing)}")
    for key in differing:
        if a[key].shape == b[key].shape:
            print(f"  {key}: max |difference| {np.nanmax(np.abs(a[key] - b[key])):.3g}")
        else:
            print(f"  {key}: {a[key].shape} rows against {b[key].shape}")
    return 1 if missing or differing else 0


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "dump":
        dump(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        raise SystemExit(compare(sys.argv[2], sys.argv[3]))
    else:
        raise SystemExit(__doc__)
