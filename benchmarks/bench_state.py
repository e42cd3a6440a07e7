"""Cost of the FMU state: fmi2GetFMUstate, fmi2SetFMUstate and serialisation per FMU.

    python benchmarks/bench_state.py [--fmu-dir DIR]

Runs bench_circle_TCMDx (and its drives-in-plant variant for ActuatedFiveBarPlant) in
``--mode fmu`` for 0.5 s, then, per instance, times getting, setting, serialising and
deserialising its state (median of 50) and prints the serialised size.
"""
from __future__ import annotations

import argparse
import statistics
import time

from fmus.export.build import ensure_built
from fmus.cosim.backends import _FmuInstance
from fmus.cosim.master import stepping_order
from fmus.cosim.stepper import Stepper
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant


def _median_us(call, rounds=50):
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return 1e6 * statistics.median(times)


def measure(system, fmu_dir, seen):
    paths = ensure_built(sorted({c.model for c in system.components}), fmu_dir)
    instances = {c.name: _FmuInstance(paths[c.model], c.name) for c in system.components}
    stepper = Stepper(system, instances, stepping_order(system, {n: i.variables for n, i in instances.items()}))
    stepper.initialize(0.0)
    for _ in range(500):
        stepper.step()
    for c in system.components:
        if c.model in seen:
            continue
        seen.add(c.model)
        inst = instances[c.name]
        state = inst.get_state()
        data = inst.serialize_state(state)
        get = _median_us(lambda: inst.free_state(inst.get_state()))
        put = _median_us(lambda: inst.set_state(state))
        ser = _median_us(lambda: inst.serialize_state(state))
        des = _median_us(lambda: inst.free_state(inst.deserialize_state(data)))
        print(f"| {c.model} | {get:.0f} | {put:.0f} | {ser:.0f} | {des:.0f} | {len(data)} |")
        inst.free_state(state)
    for inst in instances.values():
        inst.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmu-dir", default=None)
    args = parser.parse_args()
    print("| FMU | get [µs] | set [µs] | serialise [µs] | deserialise [µs] | bytes |")
    print("|---|---|---|---|---|---|")
    seen = set()
    measure(get_scene("bench_circle_TCMDx").system, args.fmu_dir, seen)
    measure(drives_in_plant(get_scene("bench_circle_TCMDx"), substeps=8).system, args.fmu_dir, seen)


if __name__ == "__main__":
    main()
