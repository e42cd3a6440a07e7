"""The shipped 5R specs against FiveBarPlant over 1 s (docs/spec.md).

``python benchmarks/spec_5r.py``: for ``thesis_sim_5r`` and ``bench_5r``, the spec-built
plant (:class:`plant.specsim.SpecSimulator`, the model of the ``parcosim build-plant``
FMU) and :class:`plant.PlantSimulator` with both kernels, from rest at (0.07, 0.17) under
the torque profile of ``tests/plant/test_spec_plant.py`` held over 1 ms steps (RK4, Baumgarte
10/s): the largest end-effector distance over the second.
"""
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from plant import IntegratorSettings, PlantSimulator, get_preset  # noqa: E402
from plant import spec as plant_spec  # noqa: E402
from plant.specsim import SpecSimulator  # noqa: E402
from tests.plant.test_spec_plant import START, torques  # noqa: E402


def compare(spec_name, preset, t_end=1.0, h=1e-3):
    ours = SpecSimulator(plant_spec.load(spec_name), (*START, 0.0))
    refs = {k: PlantSimulator(get_preset(preset), *START, IntegratorSettings(kernel=k)) for k in ("general", "fast")}
    worst = dict.fromkeys(refs, 0.0)
    t0 = time.perf_counter()
    for k in range(int(round(t_end / h))):
        u = torques(k * h)
        ours.step(u, h)
        o = ours.outputs()
        for name, ref in refs.items():
            ref.step(*u, h)
            r = ref.outputs()
            worst[name] = max(worst[name], math.hypot(o["x"] - r["x"], o["y"] - r["y"]))
    moved = math.hypot(o["x"] - START[0], o["y"] - START[1])
    print(f"{spec_name}: vs general {worst['general']:.2g} m, vs fast {worst['fast']:.2g} m over {t_end:g} s "
          f"(end effector moved {moved * 1e3:.1f} mm; {time.perf_counter() - t0:.1f} s wall for the three)")
    return worst


if __name__ == "__main__":
    compare("thesis_sim_5r", "thesis_sim")
    compare("bench_5r", "bench")
