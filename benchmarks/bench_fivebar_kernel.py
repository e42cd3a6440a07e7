"""The 5R plant step in C beside MuJoCo's RK4 on the same mechanism, and from Python.

    python benchmarks/bench_fivebar_kernel.py [--steps N]
    python benchmarks/bench_fivebar_kernel.py --against /work/main/kernels/src [--rounds 8]

Rows (µs per 1 ms step, bench preset, all measured in this run; the machine is noisy,
compare the ratios): the C step alone (``pc_fivebar_plant_io`` in a C loop,
benchmarks/fivebar_step.c, built here with the kernels' flags), MuJoCo's ``mj_step`` with
RK4 on the model of benchmarks/mujoco_5r.py in its own C loop (``nstep``), and
``PlantSimulator.step`` from Python (ctypes into the same kernel).

``--against SRC`` instead builds the C step from these sources and from the kernel sources in
SRC (another checkout's ``kernels/src``, e.g. main's) and runs the two in turn ``--rounds``
times (so load from elsewhere hits both alike), from the same start: the best CPU µs per step
of each (60 runs of 2000 steps a round) and their ratio.
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


def _start_file(folder: Path) -> Path:
    """The bench preset's parameters, settings and start state, as fivebar_step.c reads them."""
    sim = PlantSimulator(get_preset("bench"), *START)
    fast = sim._fast
    data = folder / "start.txt"
    data.write_text(" ".join(repr(float(v)) for v in [*fast.p, *fast.s, *sim.y]))
    return data


def _program(sources: Path, out: Path) -> Path:
    """fivebar_step.c with the 5R kernel of ``sources``, built with the kernels' flags."""
    flags = [f for f in build.FLAGS if f not in ("-shared", "-fPIC")]
    subprocess.run([build.compiler(), *flags, "-I", str(sources), str(HERE / "fivebar_step.c"),
                    str(sources / "fivebar.c"), "-lm", "-o", str(out)], check=True)
    return out


def _run(program: Path, data: Path, steps: int, runs: int = 7) -> float:
    out = subprocess.run([str(program), str(data), str(steps), str(runs)], capture_output=True, text=True, check=True)
    return float(out.stdout)


def c_step_us(steps: int) -> float:
    with tempfile.TemporaryDirectory() as tmp:
        return _run(_program(build.SOURCES, Path(tmp) / "fivebar_step"), _start_file(Path(tmp)), steps)


def c_step_against(other: Path, rounds: int) -> tuple:
    """(best µs per step with this checkout's kernel, with ``other``'s), in turn ``rounds`` times."""
    with tempfile.TemporaryDirectory() as tmp:
        data = _start_file(Path(tmp))
        this, that = _program(build.SOURCES, Path(tmp) / "this"), _program(other, Path(tmp) / "other")
        best = [math.inf, math.inf]
        for _ in range(rounds):
            for k, program in enumerate((this, that)):
                best[k] = min(best[k], _run(program, data, 2000, 60))
    return tuple(best)


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
    parser.add_argument("--against", type=Path, default=None, help="another kernels/src to compare the C step with")
    parser.add_argument("--rounds", type=int, default=8, help="with --against: rounds, each checkout in turn")
    args = parser.parse_args()
    if args.against is not None:
        this, other = c_step_against(args.against, args.rounds)
        print(f"| pc_fivebar_plant_io in a C loop, best CPU µs/step of {args.rounds} rounds | µs/step |")
        print("|---|---|")
        print(f"| {args.against} | {other:.4f} |")
        print(f"| this checkout ({build.SOURCES}) | {this:.4f} |")
        print(f"| ratio this / other | {this / other:.3f} |")
        return
    c, mj, py = c_step_us(args.steps), mujoco_us(args.steps), python_us(args.steps)
    print("| 5R plant step (bench preset, 1 ms, RK4) | µs/step | / MuJoCo |")
    print("|---|---|---|")
    for name, value in (("C kernel, pc_fivebar_plant_io in a C loop", c), ("MuJoCo mj_step RK4, nstep loop", mj),
                        ("PlantSimulator.step from Python (ctypes)", py)):
        print(f"| {name} | {value:.3f} | {value / mj:.3f} |")


if __name__ == "__main__":
    main()
