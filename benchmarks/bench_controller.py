"""Speed of the controller chain (Trajectory, Derivator, PositionController) and tabulation accuracy.

    python benchmarks/bench_controller.py [--steps N] [--rounds R]   # µs per 1 ms step
    python benchmarks/bench_controller.py --tabulation               # table error for 10, 5, 2.5 mm

Speed, side by side in one run (the machine is noisy): the N steps of every case are split
into R interleaved rounds; the median and the best round are reported.  Columns:

* in-process: the Python objects (``PositionController.step`` etc.);
* fmpy convenience: ``fmu.setReal(list, list)``, ``fmu.doStep``, ``fmu.getReal(list)``: fmpy
  builds ctypes arrays on every call;
* fmpy direct: how a good master calls it: ``fmu.fmi2SetReal`` / ``fmi2DoStep`` / ``fmi2GetReal``
  once per step with preallocated ctypes arrays of value references and values (all 12 inputs
  from one array prepared before the run, 4 outputs into one array);
* raw ctypes: the same with the ctypes function pointers themselves (``fmu.dll.fmi2SetReal``),
  without fmpy's Python wrapper that checks the status (what a C master pays).

The floor: a pass-through slave with the same 12 inputs and 6 outputs on the same slave base
(:class:`fmus.slave.base.GuardedSlave`, built with :mod:`fmus.export.build`'s staging), whose step only
copies inputs to outputs: the cost of the pythonfmu C++ -> Python crossing and the variable
access, which no controller through pythonfmu can undercut.

Tabulation: build time and :func:`controller.model.tabulation_error` of the default region for
each grid step (tables go to a temporary cache directory, so build times are real).
"""
import argparse
import ctypes
import math
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from controller.derivators import Derivator  # noqa: E402
from controller.model import DEFAULT_EXTENT, ExactModel, TabulatedModel, tabulation_error  # noqa: E402
from controller.position import PositionController  # noqa: E402
from controller.strategies import get_strategy  # noqa: E402
from controller.trajectories import circle  # noqa: E402
from plant import fivebar, get_preset  # noqa: E402

DT = 1e-3
BENCH = get_preset("bench")
INPUTS = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")
OUTPUTS = ("tau1", "tau2", "i_ref1", "i_ref2")
#: Slow cases (the general exact model) run this many times fewer steps.
SLOW = 50

FLOOR_SLAVE = '''"""Floor of the pythonfmu crossing: the PositionController's interface, outputs copied from inputs."""
from fmus.slave.base import GuardedSlave

INPUTS = {inputs!r}
OUTPUTS = ("tau1", "tau2", "i_ref1", "i_ref2", "e1", "e2")


class PassThrough(GuardedSlave):
    sampled = True
    author = "parcosim"
    description = "benchmark floor: 12 inputs, 6 outputs, step copies"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name in INPUTS:
            self.declare(name, "input", 0.0, name)
        for name in OUTPUTS:
            self.declare(name, "output", 0.0, name)

    def step(self, current_time, step_size):
        self.tau1, self.tau2, self.i_ref1, self.i_ref2, self.e1, self.e2 = (
            self.q1, self.q2, self.dq1, self.dq2, self.ddq1, self.ddq2)
'''


def controller_inputs(k):
    """Measurements on the bench circle, 1 mm behind the reference."""
    r = circle()(k * DT)
    ang = fivebar.inverse_kinematics(BENCH, r.x - 0.001, r.y)
    return (float(ang[0]), float(ang[2]), 0.5, -0.5, 2.0, -1.0) + tuple(r)


def run_rounds(cases, steps, rounds):
    """cases: key -> (fn(k), slow).  ``steps`` per case split into ``rounds`` interleaved rounds
    (each round times every case once, so load from elsewhere hits all cases alike).
    Returns key -> (median, min) over the rounds of µs per step."""
    per_round = max(steps // rounds, 1)
    results = {key: [] for key in cases}
    for fn, slow in cases.values():
        fn(0)                                                  # warm up (compilation, caches)
    for r in range(rounds):
        for key, (fn, slow) in cases.items():
            n = max(per_round // SLOW, 4) if slow else per_round
            start = time.perf_counter()
            for k in range(r * n, (r + 1) * n):
                fn(k)
            results[key].append((time.perf_counter() - start) / n * 1e6)
    return {key: (statistics.median(v), min(v)) for key, v in results.items()}


# --- in-process ------------------------------------------------------------------------------
CONTROLLERS = (   # (label, strategy, model, kernel)
    ("TCx tabulated", "TCx", "tabulated", "fast"),
    ("TCq tabulated", "TCq", "tabulated", "fast"),
    ("PDx (no model)", "PDx", "tabulated", "fast"),
    ("TCx exact", "TCx", "exact", "fast"),
    ("TCq exact", "TCq", "exact", "fast"),
)
REFERENCE_ONLY = (   # in-process only: the exact model by the general algorithm
    ("TCx exact, general algorithm", "TCx", "exact", "general"),
)


def in_process_cases(steps):
    inputs = [controller_inputs(k) for k in range(steps)]
    cases = {}
    for label, strategy, model, kernel in CONTROLLERS + REFERENCE_ONLY:
        ctrl = PositionController(BENCH, get_strategy(strategy), model=model, kernel=kernel)
        cases[label] = ((lambda k, c=ctrl: c.step(k * DT, *inputs[k % steps])), kernel == "general")
    d = Derivator()
    d.reset([0.1, 0.2])
    cases["Derivator"] = ((lambda k: d.step([0.1 + 1e-3 * k, 0.2])), False)
    tr = circle()
    cases["Trajectory (circle)"] = ((lambda k: tr((k + 1) * DT)), False)
    return cases


# --- through fmpy ----------------------------------------------------------------------------
class Instance:
    """One FMU instance through fmpy, set up for the three calling styles."""

    def __init__(self, path, parameters, inputs, outputs, name):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
        md = read_model_description(str(path))
        vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu = fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                                   modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        for key, value in parameters.items():
            (fmu.setString if isinstance(value, str) else fmu.setReal)([vr[key]], [value])
        fmu.exitInitializationMode()
        self.ins, self.outs = [vr[n] for n in inputs], [vr[n] for n in outputs]
        self.vr_in = (ctypes.c_uint * len(inputs))(*self.ins)
        self.vr_out = (ctypes.c_uint * len(outputs))(*self.outs)
        self.values_out = (ctypes.c_double * len(outputs))()

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def fmpy_cases(fmus, steps):
    """name -> {style: (fn, slow)} for the controller configurations, the floor and the chain."""
    from fmpy.fmi2 import fmi2True
    values = [controller_inputs(k) for k in range(steps)]
    arrays = [(ctypes.c_double * 12)(*v) for v in values]
    instances, cases = [], {}

    def add(label, inst, with_inputs, slow=False):
        fmu, c = inst.fmu, inst.fmu.component
        n_in, n_out = len(inst.ins), len(inst.outs)
        vr_in, vr_out, out = inst.vr_in, inst.vr_out, inst.values_out
        ins, outs = inst.ins, inst.outs
        f_set, f_step, f_get = fmu.fmi2SetReal, fmu.fmi2DoStep, fmu.fmi2GetReal
        r_set, r_step, r_get = fmu.dll.fmi2SetReal, fmu.dll.fmi2DoStep, fmu.dll.fmi2GetReal

        if with_inputs is None:            # no inputs (Trajectory)
            def conv(k):
                fmu.doStep(currentCommunicationPoint=k * DT, communicationStepSize=DT)
                fmu.getReal(outs)

            def direct(k):
                f_step(c, k * DT, DT, fmi2True)
                f_get(c, vr_out, n_out, out)

            def raw(k):
                r_step(c, k * DT, DT, fmi2True)
                r_get(c, vr_out, n_out, out)
        else:
            vals, arrs = with_inputs

            def conv(k):
                fmu.setReal(ins, vals[k % steps])
                fmu.doStep(currentCommunicationPoint=k * DT, communicationStepSize=DT)
                fmu.getReal(outs)

            def direct(k):
                f_set(c, vr_in, n_in, arrs[k % steps])
                f_step(c, k * DT, DT, fmi2True)
                f_get(c, vr_out, n_out, out)

            def raw(k):
                r_set(c, vr_in, n_in, arrs[k % steps])
                r_step(c, k * DT, DT, fmi2True)
                r_get(c, vr_out, n_out, out)
        cases[label] = {"convenience": (conv, slow), "direct": (direct, slow), "raw": (raw, slow)}
        instances.append(inst)

    for label, strategy, model, _ in CONTROLLERS:
        inst = Instance(fmus["PositionController"], {"strategy": strategy, "model": model},
                        INPUTS, OUTPUTS, label.replace(" ", "_"))
        add(label, inst, (values, arrays))
    floor = Instance(fmus["PassThrough"], {}, INPUTS, OUTPUTS, "floor")
    add("Pass-through floor (12 in, 4 out)", floor, (values, arrays))
    # Where the floor goes: each raw call alone.
    fc = floor.fmu.component
    r_set, r_step, r_get = floor.fmu.dll.fmi2SetReal, floor.fmu.dll.fmi2DoStep, floor.fmu.dll.fmi2GetReal
    cases["  floor: fmi2SetReal (12) alone"] = {
        "raw": ((lambda k: r_set(fc, floor.vr_in, 12, arrays[k % steps])), False)}
    cases["  floor: fmi2DoStep alone"] = {"raw": ((lambda k: r_step(fc, k * DT, DT, fmi2True)), False)}
    cases["  floor: fmi2GetReal (4) alone"] = {
        "raw": ((lambda k: r_get(fc, floor.vr_out, 4, floor.values_out)), False)}
    q = [[0.1 + 1e-3 * k, 0.2] for k in range(steps)]
    add("Derivator", Instance(fmus["Derivator"], {}, ("q1", "q2"), ("dq1", "dq2", "ddq1", "ddq2"), "der"),
        (q, [(ctypes.c_double * 2)(*v) for v in q]))
    add("Trajectory (circle)", Instance(fmus["Trajectory"], {"kind": "circle"}, (),
                                        ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d"), "traj"), None)
    return cases, instances


def build_fmus(out):
    """The three controller-chain FMUs and the floor's pass-through FMU, built into out."""
    from fmus.export.build import build_bundled_fmu, build_fmu
    paths = {name: build_fmu(name, out) for name in ("PositionController", "Derivator", "Trajectory")}
    with tempfile.TemporaryDirectory(prefix="parcosim_floor_") as tmp:
        script = Path(tmp) / "parcosim_passthrough.py"
        script.write_text(FLOOR_SLAVE.format(inputs=INPUTS))
        # on the same slave base and binary as the three above (the bundle of fmus/export/bundle.py)
        paths["PassThrough"] = build_bundled_fmu(script, "PassThrough", Path(out) / "PassThrough.fmu",
                                                 canHandleVariableCommunicationStepSize="true")
    return paths


def speed(steps, rounds):
    # Build (or load) the default tables once so that setup time is not measured.
    TabulatedModel(BENCH)
    out = Path(tempfile.mkdtemp(prefix="parcosim_bench_"))
    fmus = build_fmus(out)
    inproc = in_process_cases(steps)
    by_style, instances = fmpy_cases(fmus, steps)
    flat = {("in-process", name): case for name, case in inproc.items()}
    for name, styles in by_style.items():
        for style, case in styles.items():
            flat[(style, name)] = case
    results = run_rounds(flat, steps, rounds)
    for inst in instances:
        inst.close()

    styles = ("in-process", "convenience", "direct", "raw")
    names = list(dict.fromkeys([n for _, n in flat]))
    order = [n for n in names if n.startswith(("TC", "PD"))] + [n for n in names if not n.startswith(("TC", "PD"))]
    floor = "Pass-through floor (12 in, 4 out)"
    print(f"bench preset; {steps} steps a case in {rounds} interleaved rounds; µs per 1 ms step")
    for which, title in ((0, "median of the rounds"), (1, "best round (least disturbed)")):
        print(f"\n{title}:")
        print(f"{'component':36} {'in-process':>10} {'fmpy conv.':>10} {'fmpy direct':>11} {'raw ctypes':>10}")
        for name in order:
            cells = [results[(s, name)][which] if (s, name) in results else math.nan for s in styles]
            print(f"{name:36} " + " ".join(f"{v:{w}.1f}" if not math.isnan(v) else f"{'-':>{w}}"
                                            for v, w in zip(cells, (10, 10, 11, 10))))
        print(f"ratio to the floor in the same calling style (excess over it, µs):")
        for name in ("TCx tabulated", "TCq tabulated", "PDx (no model)", "TCx exact", "TCq exact"):
            parts = []
            for s in ("convenience", "direct", "raw"):
                v, f = results[(s, name)][which], results[(s, floor)][which]
                parts.append(f"{s} {v / f:.2f} ({v - f:+.1f})")
            print(f"  {name:34} " + ", ".join(parts))


def tabulation(steps_m=(0.01, 0.005, 0.0025), samples=400):
    os.environ["PARCOSIM_CACHE"] = tempfile.mkdtemp(prefix="parcosim_tables_")
    ExactModel(BENCH)              # load the compiled kernel first: build times without it
    print(f"region x in [{DEFAULT_EXTENT[0]}, {DEFAULT_EXTENT[1]}], y in [{DEFAULT_EXTENT[2]}, {DEFAULT_EXTENT[3]}] m, "
          f"bench preset, {samples} random points in complete cells, |dx| = 1 m/s")
    print(f"{'step mm':>8} {'points':>7} {'left out':>8} {'build s':>8}   relative error of H: median / p99 / max"
          f"   of h: median / p99 / max")
    for step in steps_m:
        tab = TabulatedModel(BENCH, step)
        err = tabulation_error(tab, samples)
        print(f"{step * 1e3:8.1f} {tab.valid.size:7d} {int((~tab.valid).sum()):8d} {tab.build_seconds:8.2f} "
              f"   {err['H_median']:.2e} / {err['H_p99']:.2e} / {err['H']:.2e}"
              f"   {err['h_median']:.2e} / {err['h_p99']:.2e} / {err['h']:.2e}", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=3000, help="steps per case (all rounds together)")
    parser.add_argument("--rounds", type=int, default=10, help="interleaved rounds")
    parser.add_argument("--tabulation", action="store_true")
    args = parser.parse_args()
    if args.tabulation:
        tabulation()
        return
    speed(args.steps, args.rounds)


if __name__ == "__main__":
    main()
