"""One model's step cost: its native FMU beside its pythonfmu twin, side by side in one run.

    python benchmarks/bench_native_step.py [MODEL ...] [--steps 1000] [--rounds 10]

Each model's two FMUs (``parcosim build --native`` and ``parcosim build``, built into a
temporary folder) are loaded in this process through fmpy, initialised with their start
values and stepped at h = 1 ms over the same second with the same varying inputs, each run
from the state saved after initialisation (fmi2SetFMUstate), alternately round after round.
Per step: ``setReal`` of the inputs, ``doStep``, ``getReal`` of every output (what a master
does), and ``doStep`` alone; CPU (``time.process_time``) per step in microseconds, the best of
the rounds.  The inputs (small, zero-mean torques or currents) keep the plant inside its
workspace, so no step is refused (fmpy raises on any status but fmi2OK).
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

#: Per model: its inputs at time t (small: the plant stays well inside its workspace).
INPUTS = {
    "FiveBarPlant": lambda t: {"tau1": 0.02 * math.sin(9.0 * t), "tau2": 0.01 * math.cos(4.0 * t)},
    "ActuatedFiveBarPlant": lambda t: {"i_ref1": 0.3 * math.sin(9.0 * t), "i_hat1": 0.3 * math.sin(9.0 * t),
                                       "i_ref2": 0.2 * math.cos(4.0 * t), "i_hat2": 0.2 * math.cos(4.0 * t)},
}
H = 1e-3


def load(path):
    """An fmpy slave of the FMU at ``path``, initialised at t = 0, its variables by name and
    its state then."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(path))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave, {v.name: v for v in md.modelVariables}, slave.getFMUstate()


def run(slave, variables, start_state, inputs, steps: int, with_io: bool) -> float:
    """CPU µs per step of ``steps`` steps from the start state (with the inputs set and the
    outputs read, or doStep alone)."""
    names = list(inputs(0.0))
    vr_in = [variables[n].valueReference for n in names]
    vr_out = [v.valueReference for v in variables.values() if v.causality == "output" and v.type == "Real"]
    values = [[inputs(k * H)[n] for n in names] for k in range(steps)]
    slave.setFMUstate(start_state)
    start = time.process_time()
    for k in range(steps):
        t = k * H
        if with_io:
            slave.setReal(vr_in, values[k])
            slave.doStep(t, H)
            slave.getReal(vr_out)
        else:
            slave.doStep(t, H)
    return (time.process_time() - start) / steps * 1e6


def bench(model: str, steps: int, rounds: int, folder: Path) -> dict:
    from fmus.export.build import build_fmu
    from fmus.native.build import build_native_fmu

    fmus = {"native": build_native_fmu(model, folder / "native"), "pythonfmu": build_fmu(model, folder / "twin")}
    slaves = {kind: load(path) for kind, path in fmus.items()}
    best = {(kind, io): math.inf for kind in fmus for io in (True, False)}
    for _ in range(rounds):
        for io in (True, False):
            for kind, (slave, variables, state) in slaves.items():
                best[kind, io] = min(best[kind, io], run(slave, variables, state, INPUTS[model], steps, io))
    for slave, _, _ in slaves.values():
        slave.terminate()
        slave.freeInstance()
    return {f"{kind} {'set+doStep+get' if io else 'doStep'}": round(us, 2) for (kind, io), us in best.items()}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="*", default=sorted(INPUTS))
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--rounds", type=int, default=10)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench_native_step_") as tmp:
        for model in args.models:
            figures = bench(model, args.steps, args.rounds, Path(tmp))
            ratio = figures["pythonfmu doStep"] / figures["native doStep"]
            print(f"{model}: CPU µs per step (best of {args.rounds} x {args.steps}): {figures}; "
                  f"doStep pythonfmu / native = {ratio:.1f}")


if __name__ == "__main__":
    main()
