"""Speed of one 1 ms plant step: in-process, through fmpy, and MuJoCo beside it.

    python benchmarks/bench_plant.py [--steps N]

Prints µs per communication step, all measured in this run, side by side (the
machine is noisy: compare the ratios).  The fmpy loop is what a master does:
setReal of the two torques, doStep, getReal of the outputs, with preallocated
value-reference lists.
"""
import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from plant import ACCURATE, IntegratorSettings, PlantSimulator, get_preset  # noqa: E402

DT = 1e-3
SETTINGS = {"default": IntegratorSettings(), "accurate": ACCURATE}
FMU_PARAMETERS = {"default": {}, "accurate": {"method": "dopri5", "rtol": 1e-12, "atol": 1e-15}}


def torques(k):
    """A 20 Hz cosine: the mechanism oscillates in place without drifting away."""
    c = math.cos(2 * math.pi * 20 * k * DT)
    return 0.02 * c, -0.02 * c


def in_process_us(settings, steps):
    sim = PlantSimulator(get_preset("bench"), 0.0, 0.17, settings)
    sim.step(0.0, 0.0, DT)
    start = time.perf_counter()
    for k in range(steps):
        sim.step(*torques(k), DT)
    return (time.perf_counter() - start) / steps * 1e6


def fmpy_us(fmu_path, parameters, steps):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu_path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setString([vr["preset"]], ["bench"])
    fmu.setReal([vr["x0"], vr["y0"]], [0.0, 0.17])
    for name, value in parameters.items():
        (fmu.setString if isinstance(value, str) else fmu.setReal)([vr[name]], [value])
    fmu.exitInitializationMode()
    inputs = [vr["tau1"], vr["tau2"]]
    outputs = [vr[n] for n in ("q1", "q2", "dq1", "dq2", "x", "y", "dx", "dy", "q1_enc", "q2_enc", "residual")]
    fmu.doStep(0.0, DT)
    start = time.perf_counter()
    for k in range(steps):
        fmu.setReal(inputs, list(torques(k)))
        fmu.doStep((k + 1) * DT, DT)
        fmu.getReal(outputs)
    elapsed = (time.perf_counter() - start) / steps * 1e6
    fmu.terminate()
    fmu.freeInstance()
    return elapsed


def mujoco_us(steps):
    try:
        from benchmarks.mujoco_5r import mujoco_step_time_us
        from tests.support.lagrange5r import params_bench
    except ImportError as exc:
        return f"n/a ({exc})"
    return mujoco_step_time_us(params_bench(), n_steps=steps)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000)
    args = parser.parse_args()
    from fmus.export.build import build_fmu

    with tempfile.TemporaryDirectory() as tmp:
        fmu = build_fmu("FiveBarPlant", Path(tmp))
        rows = []
        for name, settings in SETTINGS.items():
            rows.append((f"parcosim in-process, {name}", in_process_us(settings, args.steps)))
            rows.append((f"parcosim through fmpy, {name}", fmpy_us(fmu, FMU_PARAMETERS[name], args.steps)))
        rows.append(("MuJoCo mj_step, RK4 1 ms", mujoco_us(args.steps)))
    print("| plant step (bench preset, 1 ms) | µs/step |")
    print("|---|---|")
    for name, value in rows:
        print(f"| {name} | {value:.1f} |" if isinstance(value, float) else f"| {name} | {value} |")


if __name__ == "__main__":
    main()
