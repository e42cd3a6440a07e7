"""Speed of the controller chain (Trajectory, Derivator, PositionController) and tabulation accuracy.

    python benchmarks/bench_controller.py [--steps N]          # µs per 1 ms step
    python benchmarks/bench_controller.py --tabulation         # table error for 10, 5, 2.5 mm

Speed: in-process (the Python objects) and through fmpy (setReal of the inputs, doStep,
getReal of the outputs, preallocated value references), the controller with the exact and
the tabulated model separately (TCx and TCq, bench preset).  Tabulation: build time and
:func:`controller.model.tabulation_error` of the default region for each grid step
(tables go to a temporary cache directory, so build times are real).
"""
import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from controller.derivators import Derivator  # noqa: E402
from controller.model import DEFAULT_EXTENT, TabulatedModel, tabulation_error  # noqa: E402
from controller.position import PositionController  # noqa: E402
from controller.strategies import get_strategy  # noqa: E402
from controller.trajectories import circle  # noqa: E402
from plant import fivebar, get_preset  # noqa: E402

DT = 1e-3
BENCH = get_preset("bench")
INPUTS = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")


def controller_inputs(k):
    """Measurements on the bench circle, 1 mm behind the reference."""
    r = circle()(k * DT)
    ang = fivebar.inverse_kinematics(BENCH, r.x - 0.001, r.y)
    return (float(ang[0]), float(ang[2]), 0.5, -0.5, 2.0, -1.0) + tuple(r)


def timed(fn, steps):
    fn(0)
    start = time.perf_counter()
    for k in range(steps):
        fn(k)
    return (time.perf_counter() - start) / steps * 1e6


def in_process(steps):
    rows = {}
    inputs = [controller_inputs(k) for k in range(steps)]
    for strategy in ("TCx", "TCq", "PDx"):
        for model in ("tabulated", "exact"):
            if strategy == "PDx" and model == "exact":
                continue
            ctrl = PositionController(BENCH, get_strategy(strategy), model=model)
            n = steps if model == "tabulated" else max(steps // 50, 20)
            rows[f"PositionController {strategy} {model if strategy != 'PDx' else '(no model)'}"] = timed(
                lambda k: ctrl.step(k * DT, *inputs[k % steps]), n)
    d = Derivator()
    d.reset([0.1, 0.2])
    rows["Derivator"] = timed(lambda k: d.step([0.1 + 1e-3 * k, 0.2]), steps)
    tr = circle()
    rows["Trajectory (circle)"] = timed(lambda k: tr((k + 1) * DT), steps)
    return rows


def through_fmpy(steps):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    from fmus.build import build_fmu

    rows = {}
    out = Path(tempfile.mkdtemp(prefix="parcosim_bench_"))

    def instance(model, parameters):
        path = build_fmu(model, out) if not (out / f"{model}.fmu").exists() else out / f"{model}.fmu"
        md = read_model_description(str(path))
        vr = {v.name: v.valueReference for v in md.modelVariables}
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName=model)
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        for name, value in parameters.items():
            (fmu.setString if isinstance(value, str) else fmu.setReal)([vr[name]], [value])
        fmu.exitInitializationMode()
        return fmu, vr

    inputs = [controller_inputs(k) for k in range(steps)]
    for strategy, model in (("TCx", "tabulated"), ("TCq", "tabulated"), ("PDx", "tabulated"), ("TCx", "exact")):
        fmu, vr = instance("PositionController", {"strategy": strategy, "model": model})
        ins = [vr[n] for n in INPUTS]
        outs = [vr[n] for n in ("tau1", "tau2", "i_ref1", "i_ref2")]

        def step(k, fmu=fmu, ins=ins, outs=outs):
            fmu.setReal(ins, inputs[k % steps])
            fmu.doStep(currentCommunicationPoint=k * DT, communicationStepSize=DT)
            fmu.getReal(outs)
        n = steps if model == "tabulated" else max(steps // 50, 20)
        label = "(no model)" if strategy == "PDx" else model
        rows[f"PositionController {strategy} {label}"] = timed(step, n)
        fmu.terminate()
        fmu.freeInstance()
    fmu, vr = instance("Derivator", {})
    ins, outs = [vr["q1"], vr["q2"]], [vr[n] for n in ("dq1", "dq2", "ddq1", "ddq2")]

    def dstep(k):
        fmu.setReal(ins, [0.1 + 1e-3 * k, 0.2])
        fmu.doStep(currentCommunicationPoint=k * DT, communicationStepSize=DT)
        fmu.getReal(outs)
    rows["Derivator"] = timed(dstep, steps)
    fmu, vr = instance("Trajectory", {"kind": "circle"})
    outs = [vr[n] for n in ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")]

    def tstep(k):
        fmu.doStep(currentCommunicationPoint=k * DT, communicationStepSize=DT)
        fmu.getReal(outs)
    rows["Trajectory (circle)"] = timed(tstep, steps)
    return rows


def tabulation(steps_m=(0.01, 0.005, 0.0025), samples=400):
    os.environ["PARCOSIM_CACHE"] = tempfile.mkdtemp(prefix="parcosim_tables_")
    print(f"region x in [{DEFAULT_EXTENT[0]}, {DEFAULT_EXTENT[1]}], y in [{DEFAULT_EXTENT[2]}, {DEFAULT_EXTENT[3]}] m, "
          f"bench preset, {samples} random points in complete cells, |dx| = 1 m/s")
    print(f"{'step mm':>8} {'points':>7} {'left out':>8} {'build s':>8}   relative error of H: median / p99 / max"
          f"   of h: median / p99 / max")
    for step in steps_m:
        tab = TabulatedModel(BENCH, step)
        err = tabulation_error(tab, samples)
        print(f"{step * 1e3:8.1f} {tab.valid.size:7d} {int((~tab.valid).sum()):8d} {tab.build_seconds:8.1f} "
              f"   {err['H_median']:.2e} / {err['H_p99']:.2e} / {err['H']:.2e}"
              f"   {err['h_median']:.2e} / {err['h_p99']:.2e} / {err['h']:.2e}", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--tabulation", action="store_true")
    args = parser.parse_args()
    if args.tabulation:
        tabulation()
        return
    # Build (or load) the default tables once so that setup time is not measured.
    TabulatedModel(BENCH)
    a, b = in_process(args.steps), through_fmpy(args.steps)
    print(f"{'component':44} {'in-process µs':>14} {'fmpy µs':>10}")
    for name in a:
        print(f"{name:44} {a[name]:14.1f} {b.get(name, math.nan):10.1f}")


if __name__ == "__main__":
    main()
