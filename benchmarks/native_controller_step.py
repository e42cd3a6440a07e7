"""CPU per step of the PositionController FMU, native beside pythonfmu, in one process (issue 28).

    python benchmarks/native_controller_step.py [--strategy TCMDx] [--model tabulated] [--steps 2000] [--rounds 5]

Both FMUs (``parcosim build`` and ``parcosim build --native``; ``strategy`` and ``model`` set
before initialisation) are instantiated through fmpy in this process and fed the same circle
references and measured angles near them.  Each round runs, for each FMU in turn, ``--steps`` steps of h = T (set the
12 inputs, ``doStep``, read the 6 Real outputs); each ``doStep`` is timed (``doStep`` and its
ctypes call, ``time.process_time_ns``, less a back-to-back timer pair), in CPU microseconds per
step, the best of ``--rounds``.  A floor beside them: the same loop on the C low-pass of
benchmarks/baseline_fmu (next to nothing to compute: fmpy's and ctypes' share of a call).
Prints a markdown table.
"""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FLOOR = "floor: the C low-pass of benchmarks/baseline_fmu"
INPUTS = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")
OUTPUTS = ("tau1", "tau2", "i_ref1", "i_ref2", "e1", "e2")


def input_rows(steps: int, T: float) -> list:
    """Per step the 12 inputs: the circle's reference and the angles of a pose 2 mm beside it."""
    from controller.kinematics import Kinematics
    from controller.trajectories import get_trajectory
    from plant import get_preset

    kin, circle = Kinematics(get_preset("bench")), get_trajectory("circle")
    rows = []
    for k in range(steps):
        t = k * T
        r = circle(t)
        a = kin.inverse(r.x + 0.002 * math.sin(11.0 * t), r.y - 0.001 * math.cos(7.0 * t))
        rows.append([a[0], a[2], 0.1, -0.1, 0.0, 0.0, r.x, r.y, r.dx, r.dy, r.ddx, r.ddy])
    return rows


def instance(path: Path, work: Path, strategy: str | None = None, model: str | None = None):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(path))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path), str(work)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    slave.instantiate()
    refs = {v.name: v.valueReference for v in md.modelVariables}
    if strategy is None:   # the floor: the C low-pass, one input and one output
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        return slave, [refs["u"]] * len(INPUTS), [refs["y"]] * len(OUTPUTS)
    slave.setString([refs["strategy"], refs["model"]], [strategy, model])
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave, [refs[n] for n in INPUTS], [refs[n] for n in OUTPUTS]


def step_cpu(slave, inputs, outputs, rows, T, start_step) -> float:
    """CPU seconds in the doStep calls alone (each timed), less the timer's own cost."""
    clock, spent, idle = time.process_time_ns, 0, 0
    for k, row in enumerate(rows):
        slave.setReal(inputs, row)
        c0 = clock()
        slave.doStep((start_step + k) * T, T)
        c1 = clock()
        c2 = clock()
        spent += c1 - c0
        idle += c2 - c1
        slave.getReal(outputs)
    return (spent - idle) * 1e-9


def main(argv=None) -> int:
    from benchmarks.cold_start import build_baseline
    from fmus.build import build_fmu
    from fmus.native.build import build_native_fmu

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--strategy", default="TCMDx")
    parser.add_argument("--model", default="tabulated", choices=("tabulated", "exact"))
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    T = 1e-3
    with tempfile.TemporaryDirectory(prefix="pc_step_") as tmp:
        work = Path(tmp)
        fmus = {"pythonfmu": build_fmu("PositionController", work / "twin"),
                "native": build_native_fmu("PositionController", work / "native")}
        slaves = {kind: instance(path, work / kind, args.strategy, args.model) for kind, path in fmus.items()}
        (work / "floor").mkdir()
        slaves[FLOOR] = instance(build_baseline(work / "floor"), work / "floor")
        rows = input_rows(args.steps * (args.rounds + 1), T)
        best = {kind: math.inf for kind in slaves}
        for r in range(args.rounds):
            chunk = rows[r * args.steps:(r + 1) * args.steps]
            for kind, (slave, ins, outs) in slaves.items():
                best[kind] = min(best[kind], step_cpu(slave, ins, outs, chunk, T, r * args.steps) / args.steps)
        for slave, _, _ in slaves.values():
            slave.terminate()
            slave.freeInstance()
    print(f"PositionController {args.strategy}, {args.model} model, h = T = 1 ms, {args.steps} steps a round, "
          f"best of {args.rounds}")
    floor = best[FLOOR]
    print("| FMU | CPU per doStep (µs) | less the floor (µs) |\n|---|---:|---:|")
    for kind, cpu in best.items():
        print(f"| {kind} | {cpu * 1e6:.2f} | {(cpu - floor) * 1e6:.2f} |")
    print(f"| ratio pythonfmu / native | {best['pythonfmu'] / best['native']:.1f} | "
          f"{(best['pythonfmu'] - floor) / (best['native'] - floor):.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
