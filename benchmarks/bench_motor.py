"""Cost of one 1 ms step of the motor drive and the current observer.

In process (``motor.Drive.step``, ``motor.CurrentObserver.estimate``) and
through fmpy (``DCMotorDrive`` and ``CurrentObserver`` FMUs), the way a
master drives them each step:

* ``fmpy``: ``FMU2Slave.setReal / doStep / getReal`` with preallocated
  value-reference lists (fmpy builds the ctypes arrays on every call);
* ``fmpy raw``: fmpy's status-checked ctypes functions ``fmi2SetReal /
  fmi2DoStep / fmi2GetReal`` with preallocated ctypes arrays.

Goal: <= 15 us per step through fmpy, each.

    python benchmarks/bench_motor.py [--steps N] [--repeat R] [--fmu-dir DIR]

Without ``--fmu-dir`` the two FMUs are built into a temporary directory.
Models and FMU instances are created once, outside the timing; the R rounds
run every case in turn for N steps and the best round is printed, in
microseconds per step (best-of, since other load on the machine only ever
adds time).
"""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from fmpy import extract, instantiate_fmu, read_model_description  # noqa: E402
from fmpy.fmi2 import fmi2Real, fmi2True, fmi2ValueReference  # noqa: E402

from motor import CurrentObserver, Drive, motor1  # noqa: E402

T = 1e-3
GOAL_US = 15.0
#: The same held inputs in process and through fmpy.
DRIVE_INPUTS = {"i_ref": 0.5, "omega": 10.0, "i_hat": 0.5}    # tracking: controller unsaturated
DRIVE_OUTPUTS = ("tau", "v", "i")
OBSERVER_INPUTS = {"v": 1.0, "omega": 10.0}
OBSERVER_OUTPUTS = ("i_hat",)


def inprocess_drive():
    step, u = Drive(motor1).step, DRIVE_INPUTS

    def run(steps):
        for _ in range(steps):
            step(u["i_ref"], 0.0, u["omega"], u["i_hat"], T)
    return run


def inprocess_observer():
    estimate, u = CurrentObserver(motor1).estimate, OBSERVER_INPUTS

    def run(steps):
        for _ in range(steps):
            estimate(u["v"], u["omega"], T)
    return run


def open_fmu(path):
    """Instantiate and initialise an FMU with its default parameters; return (slave, {name: vr})."""
    md = read_model_description(str(path))
    slave = instantiate_fmu(extract(str(path)), md)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave, {v.name: v.valueReference for v in md.modelVariables}


def fmpy_loop(slave, vrs, inputs, outputs):
    """setReal / doStep / getReal with preallocated value-reference lists."""
    vr_in, values = [vrs[n] for n in inputs], list(inputs.values())
    vr_out = [vrs[n] for n in outputs]
    set_real, do_step, get_real = slave.setReal, slave.doStep, slave.getReal
    clock = {"t": 0.0}

    def run(steps):
        t = clock["t"]
        for _ in range(steps):
            set_real(vr_in, values)
            do_step(t, T)
            get_real(vr_out)
            t += T
        clock["t"] = t
    return run


def fmpy_raw_loop(slave, vrs, inputs, outputs):
    """fmi2SetReal / fmi2DoStep / fmi2GetReal with preallocated ctypes arrays."""
    n_in, n_out = len(inputs), len(outputs)
    c_in = (fmi2ValueReference * n_in)(*(vrs[n] for n in inputs))
    c_values = (fmi2Real * n_in)(*inputs.values())
    c_out = (fmi2ValueReference * n_out)(*(vrs[n] for n in outputs))
    c_result = (fmi2Real * n_out)()
    component = slave.component
    set_real, do_step, get_real = slave.fmi2SetReal, slave.fmi2DoStep, slave.fmi2GetReal
    clock = {"t": 0.0}

    def run(steps):
        t = clock["t"]
        for _ in range(steps):
            set_real(component, c_in, n_in, c_values)
            do_step(component, t, T, fmi2True)
            get_real(component, c_out, n_out, c_result)
            t += T
        clock["t"] = t
    return run


def measure(cases, steps, repeat):
    """Best time per step [us] of each run(steps), the cases interleaved round by round."""
    best = [math.inf] * len(cases)
    for _ in range(repeat):
        for k, (_, _, run) in enumerate(cases):
            t0 = time.perf_counter()
            run(steps)
            best[k] = min(best[k], time.perf_counter() - t0)
    return [1e6 * b / steps for b in best]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=30)
    ap.add_argument("--fmu-dir", type=Path, default=None, help="directory with built FMUs (default: build now)")
    args = ap.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="bench_motor_") as tmp:
        fmu_dir = args.fmu_dir
        if fmu_dir is None:
            from fmus.export.build import build_fmu
            fmu_dir = Path(tmp)
            for model in ("DCMotorDrive", "CurrentObserver"):
                build_fmu(model, fmu_dir)
        drive, drive_vrs = open_fmu(fmu_dir / "DCMotorDrive.fmu")
        observer, observer_vrs = open_fmu(fmu_dir / "CurrentObserver.fmu")
        cases = [
            ("Drive.step (current mode)", "in-process", inprocess_drive()),
            ("CurrentObserver.estimate", "in-process", inprocess_observer()),
            ("DCMotorDrive (current mode)", "fmpy", fmpy_loop(drive, drive_vrs, DRIVE_INPUTS, DRIVE_OUTPUTS)),
            ("CurrentObserver (static)", "fmpy",
             fmpy_loop(observer, observer_vrs, OBSERVER_INPUTS, OBSERVER_OUTPUTS)),
            ("DCMotorDrive (current mode)", "fmpy raw",
             fmpy_raw_loop(drive, drive_vrs, DRIVE_INPUTS, DRIVE_OUTPUTS)),
            ("CurrentObserver (static)", "fmpy raw",
             fmpy_raw_loop(observer, observer_vrs, OBSERVER_INPUTS, OBSERVER_OUTPUTS)),
        ]
        times = measure(cases, args.steps, args.repeat)
        for slave in (drive, observer):
            slave.terminate()
            slave.freeInstance()

    print(f"{'component':<30} {'through':<11} {'us/step':>8}   goal through fmpy <= {GOAL_US:g} us")
    for (name, how, _), us in zip(cases, times):
        flag = "" if how == "in-process" else ("  ok" if us <= GOAL_US else "  over")
        print(f"{name:<30} {how:<11} {us:8.2f}{flag}")
    print(f"best of {args.repeat} rounds of {args.steps} steps of {T * 1e3:g} ms; Python {sys.version.split()[0]}")


if __name__ == "__main__":
    main()
