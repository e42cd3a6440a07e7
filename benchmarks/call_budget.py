"""The costs behind the work limit of one FMI call (fmus/slave/budget.py).

    python -m benchmarks.call_budget [--repeat N]

Measures the CPU (``time.process_time``, the best of N runs) of one unit of every kind of
work an FMI call counts: a right-hand side of each integrator and kernel, and an inner step
of a system FMU; prints each beside the cost fmus/slave/budget.py charges for it and the units one
call may take at that cost (about a second of CPU).  A measured cost above the charged one
means the limit lets a call run longer than a second here: raise the constant.  The figures
are in docs/plant.md ("The work of one call").
"""
from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from fmus.slave import budget
from plant import IntegratorSettings, PlantSimulator, get_preset
from plant import spec as plant_spec
from plant.specsim import SpecSimulator

#: A dopri5 step this long takes a few hundred evaluations (enough to time).
LONG_STEP = 0.05
START = (0.07, 0.17)


def best_cpu(run, repeat: int) -> float:
    """The least CPU [s] of ``repeat`` calls of ``run``."""
    best = float("inf")
    for _ in range(repeat):
        start = time.process_time()
        run()
        best = min(best, time.process_time() - start)
    return best


def joints_of(mechanism) -> int:
    return sum(len(chain.joints) for chain in mechanism.chains)


def five_bar(kernel: str, method: str, substeps: int = 1) -> PlantSimulator:
    params = replace(get_preset("thesis_sim"), gravity=(0.0, -9.81, 0.0))
    return PlantSimulator(params, *START, IntegratorSettings(method=method, kernel=kernel, substeps=substeps))


def per_evaluation(step, repeat: int) -> float:
    """CPU of one right-hand side: ``step()`` returns the evaluations it took, each from the
    same state (a fresh copy is stepped)."""
    counts = []
    cpu = best_cpu(lambda: counts.append(step()), repeat)
    return cpu / counts[-1]


def plant_step(make):
    """A step of LONG_STEP from a fresh plant (made by ``make``) with torques held."""
    def step():
        sim = make()
        return sim.step(0.02, -0.01, LONG_STEP)
    return step


def spec_step(name: str, method: str):
    spec = plant_spec.load(name)
    settings = IntegratorSettings(method=method, kernel="general", substeps=50)
    template = SpecSimulator(spec, None, settings)

    def step():
        sim = SpecSimulator.__new__(SpecSimulator)
        vars(sim).update(vars(template), y=template.y.copy())
        return sim.step(np.full(len(spec.inputs), 0.01), LONG_STEP)
    return step, joints_of(template.mechanism)


def actuated_step(method: str, substeps: int = 1, kernel: str = "fast"):
    from motor import Drive, get_motor_preset
    from plant.actuated import ActuatedPlant

    def step():
        drives = [(j, Drive(get_motor_preset(f"motor{j}"), mode="voltage")) for j in (1, 2)]
        plant = ActuatedPlant(five_bar(kernel, method, substeps), drives)
        return plant.step((0.0, 0.0), (0.0, 0.0), (2.0, -1.0), LONG_STEP)
    return step


def wheeled_step(substeps: int = 10000):
    from plant.wheeled import WheeledPendulum

    sim = WheeledPendulum(substeps=substeps)

    def step():
        sim.step(0.0, 0.0, 1e-3)
        return 4 * substeps
    return step


def inner_step(scene: str, steps: int = 200):
    """CPU of one inner doStep of ``scene``'s ClosedLoop (its components' steps, the plant's
    evaluations included) over ``steps`` communication steps."""
    from fmus.systemfmu.cores import LoopCore
    from scenarios.scenes.catalogue import get_scene

    system = get_scene(scene).system
    per_step = sum(c.substeps for c in system.components)

    def run():
        core = LoopCore(system)
        core.initialize()
        start = time.process_time()
        for k in range(steps):
            core.step(k * system.step, system.step)
        return time.process_time() - start
    return lambda: run() / (steps * per_step)


def rows(repeat: int):
    """(what, measured cost [s], charged cost [s]) of every kind of unit."""
    fast_dopri5 = budget.FAST_DOPRI5_EVALUATION
    general = budget.plant_evaluation_cost
    out = [
        ("5R fast kernel, RK4 (compiled), 1 evaluation",
         per_evaluation(plant_step(lambda: five_bar("fast", "rk4", 1000)), repeat), budget.FAST_RK4_EVALUATION),
        ("5R + drives fast kernel, RK4 (compiled)", per_evaluation(actuated_step("rk4", 1000), repeat),
         budget.FAST_RK4_EVALUATION),
        ("5R fast kernel, dopri5", per_evaluation(plant_step(lambda: five_bar("fast", "dopri5")), repeat),
         fast_dopri5),
        ("5R + drives fast kernel, dopri5", per_evaluation(actuated_step("dopri5"), repeat), fast_dopri5),
        ("5R general kernel (4 joints), dopri5, gravity_y",
         per_evaluation(plant_step(lambda: five_bar("general", "dopri5")), repeat), general("general", "dopri5", 4)),
        ("5R + drives general kernel (4 joints), dopri5, gravity_y",
         per_evaluation(actuated_step("dopri5", kernel="general"), repeat), general("general", "dopri5", 4)),
        ("5R general kernel (4 joints), RK4, gravity_y",
         per_evaluation(plant_step(lambda: five_bar("general", "rk4", 20)), repeat), general("general", "rk4", 4)),
    ]
    for name in ("bench_5r", "delta3"):
        for method in ("dopri5", "rk4"):
            step, joints = spec_step(name, method)
            out.append((f"SpecPlant {name} ({joints} joints), {method}", per_evaluation(step, repeat),
                        general("general", method, joints)))
    out.append(("WheeledPendulum RK4 (compiled)", per_evaluation(wheeled_step(), repeat),
                budget.WHEELED_RK4_EVALUATION))
    for scene in ("thesis_sim_circle", "bench_circle_TCMDx", "bench_real_circle_TCMDx", "vertical_circle_SMCx",
                  "pendulum_balance"):
        out.append((f"inner step of ClosedLoop {scene}", min(inner_step(scene)() for _ in range(repeat)),
                    budget.INNER_STEP))
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per figure (the best counts)")
    args = parser.parse_args(argv)
    print(f"one call may take {budget.CALL_CPU_SECONDS:g} s of CPU (counted)")
    print(f"{'unit of work':58s} {'measured':>10s} {'charged':>10s} {'per call':>9s}")
    for what, measured, charged in rows(args.repeat):
        flag = "  <- measured above charged" if measured > charged else ""
        print(f"{what:58s} {measured * 1e6:8.3g} µs {charged * 1e6:8.3g} µs {budget.per_call(charged):9d}{flag}")


if __name__ == "__main__":
    main()
