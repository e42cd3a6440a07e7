"""The 5R plant step in C beside MuJoCo's RK4 on the same mechanism, and from Python.

    python benchmarks/bench_fivebar_kernel.py [--steps N]

Rows (µs per 1 ms step, bench preset, all measured in this run; the machine is noisy,
compare the ratios): the C step alone (``pc_fivebar_plant_io`` in a C loop,
benchmarks/fivebar_step.c, built here with the kernels' flags), MuJoCo's ``mj_step`` with
RK4 on the model of benchmarks/mujoco_5r.py in its own C loop (``nstep``), and
``PlantSimulator.step`` from Python (ctypes into the same kernel).
"""
import argparse
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from kernels import build  # noqa: E402
from plant import PlantSimulator, get_preset  # noqa: E402

START = (0.0, 0.17)


def c_step_us(steps: int) -> float:
    sim = PlantSimulator(get_preset("bench"), *START)
    fast = sim._fast
    with tempfile.TemporaryDirectory() as tmp:
        program, data = Path(tmp) / "fivebar_step", Path(tmp) / "start.txt"
        data.write_text(" ".join(repr(float(v)) for v in [*fast.p, *fast.s, *sim.y]))
        flags = [f for f in build.FLAGS if f not in ("-shared", "-fPIC")]
        subprocess.run([build.compiler(), *flags, "-I", str(build.SOURCES), str(HERE / "fivebar_step.c"),
                        str(build.SOURCES / "fivebar.c"), "-lm", "-o", str(program)], check=True)
        out = subprocess.run([str(program), str(data), str(steps)], capture_output=True, text=True, check=True)
    return float(out.stdout)


def mujoco_us(steps: int) -> float:
    import mujoco

    from benchmarks.mujoco_5r import TIMING_START, TIMING_STEPS_PER_RUN, TIMING_TORQUES, mjcf_5r, \
        mujoco_initial_state
    from tests.support.lagrange5r import params_bench

    params = params_bench()
    model = mujoco.MjModel.from_xml_string(mjcf_5r(params, integrator="RK4"))
    data = mujoco.MjData(model)
    q0 = mujoco_initial_state(params, *TIMING_START)
    best = math.inf
    for _ in range(7):
        elapsed, left = 0.0, steps
        while left > 0:
            n = min(TIMING_STEPS_PER_RUN, left)
            mujoco.mj_resetData(model, data)
            data.qpos[:] = q0
            data.ctrl[:] = TIMING_TORQUES
            start = time.perf_counter()
            mujoco.mj_step(model, data, nstep=n)
            elapsed += time.perf_counter() - start
            left -= n
        best = min(best, elapsed / steps * 1e6)
    return best


def python_us(steps: int) -> float:
    best = math.inf
    for _ in range(7):
        sim = PlantSimulator(get_preset("bench"), *START)
        start = time.perf_counter()
        for k in range(steps):
            torque = 0.02 * math.cos(2 * math.pi * 20 * k * 1e-3)
            sim.step(torque, -torque, 1e-3)
        best = min(best, (time.perf_counter() - start) / steps * 1e6)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000)
    args = parser.parse_args()
    c, mj, py = c_step_us(args.steps), mujoco_us(args.steps), python_us(args.steps)
    print("| 5R plant step (bench preset, 1 ms, RK4) | µs/step | / MuJoCo |")
    print("|---|---|---|")
    for name, value in (("C kernel, pc_fivebar_plant_io in a C loop", c), ("MuJoCo mj_step RK4, nstep loop", mj),
                        ("PlantSimulator.step from Python (ctypes)", py)):
        print(f"| {name} | {value:.3f} | {value / mj:.3f} |")


if __name__ == "__main__":
    main()
