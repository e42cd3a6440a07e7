"""Where a compiled step's time goes, member by member, measured inside the running loop.

    python benchmarks/profile_members.py [--scene bench_circle_TCMDx] [--repeats 5]

``--repeats`` pairs of runs of ``--scene`` in the compiled mode (``simulate(system,
mode="compiled")``), in turn:

* **untimed**: the run as it is; each chunk's CPU time of the thread per step (the compiled mode
  steps in chunks of 1 % of the run; the first chunk, cold, is left out);
* **timed**: every member's I/O step replaced in the loop's plan by ``pc_timed_io``
  (benchmarks/member_timer.c, built here with the kernels' flags), which calls the member's own
  step with its own context and adds the time-stamp counter's ticks of the call to the member's
  tally; rows, state and results are the run's own (checked: a timed run's rows differing from
  the untimed run's stop the tool).

Printed: per member its kernel and its ns a call inside the loop (the timer's own cost, the
tally of a member that does nothing timed the same way, taken off), and its share of the
untimed step; then the loop's own part (copying inputs and outputs between the members' arrays
and the value slots, recording the row, calling through the plan's pointers): the untimed step
minus the members' sum.  Last, that part alone: the run's plan with every member's step replaced
by one that does nothing (``pc_timed_nothing``), all the run's steps in one call, with the
recorded row and without it (``n_record`` 0): minimum and median CPU ns per step of
``--repeats`` x 2 runs.  The counter's ticks are turned into ns against ``time.perf_counter_ns``
over the runs.  On a shared machine read the shares, and compare builds with
bench_compiled_ab.py (the load average is printed).
"""
from __future__ import annotations

import argparse
import ctypes
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from kernels import build  # noqa: E402

#: Steps of the timer's calibration (a member that does nothing).
CALIBRATION_STEPS = 20000
#: A call timed longer than this is not counted (the thread was descheduled meanwhile), ns.
CAP_NS = 20000


class _Timed(ctypes.Structure):
    """``pc_timed_member`` of member_timer.c."""

    _fields_ = [("io", ctypes.c_void_p), ("context", ctypes.c_void_p), ("ticks", ctypes.c_double),
                ("calls", ctypes.c_double), ("cap", ctypes.c_double), ("dropped", ctypes.c_double)]


def timer_library(folder: Path) -> ctypes.CDLL:
    """member_timer.c built into ``folder`` with the kernels' flags."""
    out = folder / "member_timer.so"
    subprocess.run([build.compiler(), *build.FLAGS, f"-I{build.SOURCES}", str(Path(__file__).with_name("member_timer.c")),
                    "-o", str(out)], check=True)
    lib = ctypes.CDLL(str(out))
    lib.pc_timed_now.restype = ctypes.c_double
    return lib


def _address(lib, name: str) -> int:
    return ctypes.cast(getattr(lib, name), ctypes.c_void_p).value


def ticks_per_ns(timer, seconds: float = 0.05) -> float:
    """The counter's rate against ``time.perf_counter_ns``."""
    ticks0, ns0 = timer.pc_timed_now(), time.perf_counter_ns()
    while time.perf_counter_ns() - ns0 < seconds * 1e9:
        pass
    return (timer.pc_timed_now() - ticks0) / (time.perf_counter_ns() - ns0)


def calibration(timer, per_ns: float, steps: int = CALIBRATION_STEPS) -> float:
    """The timer's own ticks a call: a member that does nothing, timed, in a one-member loop."""
    import numpy as np

    from fmus.cosim import compiled

    tally = _Timed(_address(timer, "pc_timed_nothing"), None, 0.0, 0.0, CAP_NS * per_ns, 0.0)
    x = np.zeros(1)
    loop = compiled.LoopPlan([(1, [compiled.Member(_address(timer, "pc_timed_io"), ctypes.addressof(tally), x)])],
                             [])
    loop.run(np.zeros(1), np.zeros((steps + 1, 1)), 0, steps, 0.0, 1e-3)
    return tally.ticks / tally.calls


def profile(scene, timer, repeats: int, per_ns: float) -> dict:
    """Untimed chunks' CPU ns per step; per timed run the members' (ticks, calls, dropped)."""
    from fmus.cosim import compiled
    from fmus.cosim.master import simulate

    state = {"timed": False, "tallies": None}
    chunks, tallies, names, rows = [], [], [], {}
    original = compiled.Plan.run

    def run(plan, values, record, k0, k1, t, h):
        state["plan"] = plan
        if state["timed"] and state["tallies"] is None:
            pointers = plan.loop._pointers
            items = [_Timed(int(io), int(ctx), 0.0, 0.0, CAP_NS * per_ns, 0.0)
                     for io, ctx in zip(pointers["io"], pointers["context"])]
            state["tallies"] = items
            names[:] = [f"{a.name} ({a.kernel})" for a in plan.adapters]
            pointers["io"][:] = _address(timer, "pc_timed_io")
            pointers["context"][:] = [ctypes.addressof(item) for item in items]
        start = time.thread_time_ns()
        stop = original(plan, values, record, k0, k1, t, h)
        if not state["timed"] and k0 > 0 and stop.step > k0:
            chunks.append((time.thread_time_ns() - start) / (stop.step - k0))
        return stop

    compiled.Plan.run = run
    try:
        for _ in range(repeats):
            for timed in (False, True):
                state.update(timed=timed, tallies=None)
                result = simulate(scene.system, mode="compiled")
                if result.error or not result.completed or result.extra.get("python_steps"):
                    raise RuntimeError(f"compiled run: {result.error or 'not completed in C'}")
                rows[timed] = result.signals
                if timed:
                    tallies.append([(item.ticks, item.calls, item.dropped) for item in state["tallies"]])
                    if any(rows[True][k].tobytes() != rows[False][k].tobytes() for k in rows[False]):
                        raise RuntimeError("a timed run's rows differ from the untimed run's")
    finally:
        compiled.Plan.run = original
    return {"chunks": chunks, "tallies": tallies, "names": names, "plan": state["plan"]}


def hollow(plan, timer, steps: int, runs: int) -> dict:
    """CPU ns per step of ``plan``'s loop with every member's step doing nothing, with the
    row recorded and without: (minimum, median) of ``runs`` runs of ``steps`` steps each."""
    import numpy as np

    pointers, struct = plan.loop._pointers, plan.loop.struct
    pointers["io"][:] = _address(timer, "pc_timed_nothing")
    values = np.zeros(max(int(np.max(plan.loop._arrays[name], initial=0)) for name in ("in_slot", "out_slot",
                                                                                      "record_slot")) + 1)
    n_record, found = struct.n_record, {}
    for label, recorded in (("with the row", n_record), ("without the row", 0)):
        struct.n_record = recorded
        record = np.zeros((steps + 1, max(n_record, 1)))
        times = []
        for _ in range(runs):
            start = time.thread_time_ns()
            plan.loop.run(values, record, 0, steps, 0.0, 1e-3)
            times.append((time.thread_time_ns() - start) / steps)
        found[label] = (min(times), statistics.median(times))
    struct.n_record = n_record
    return found


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="bench_circle_TCMDx")
    parser.add_argument("--repeats", type=int, default=5, help="pairs of runs, untimed and timed (default 5)")
    args = parser.parse_args(argv)
    from scenarios.scenes.catalogue import get_scene

    with tempfile.TemporaryDirectory() as tmp:
        timer = timer_library(Path(tmp))
        scene = get_scene(args.scene)
        per_ns = ticks_per_ns(timer)
        found = profile(scene, timer, args.repeats, per_ns)
        own = calibration(timer, per_ns)
        alone = hollow(found["plan"], timer, scene.system.steps, 2 * args.repeats)
    names = found["names"]
    step = statistics.median(found["chunks"])
    # per member: the median over the timed runs of its ns a call, the timer's own cost off
    members = [statistics.median((run[n][0] / run[n][1] - own) / per_ns for run in found["tallies"])
               for n in range(len(names))]
    dropped = sum(run[n][2] for run in found["tallies"] for n in range(len(names)))
    calls = sum(run[n][1] for run in found["tallies"] for n in range(len(names)))
    load = "/".join(f"{v:.2f}" for v in os.getloadavg())
    print(f"{args.scene}, compiled, {args.repeats} untimed + {args.repeats} timed runs, load average {load}; "
          f"untimed step {step:.0f} ns (median of {len(found['chunks'])} chunks, CPU), timer {own / per_ns:.0f} ns "
          f"a call taken off, {dropped:.0f} of {calls + dropped:.0f} timed calls > {CAP_NS / 1000:.0f} µs left out")
    print("| member (kernel) | ns a call in the loop | share of the step |")
    print("|---|---:|---:|")
    for name, ns in zip(names, members):
        print(f"| {name} | {ns:.0f} | {100 * ns / step:.1f} % |")
    rest = step - sum(members)
    print(f"| the loop's own (copies, row, calls) | {rest:.0f} | {100 * rest / step:.1f} % |")
    print(f"| step (untimed) | {step:.0f} | 100 % |")
    print("\n| the loop alone, members doing nothing | CPU ns a step, min | median |")
    print("|---|---:|---:|")
    for label, (least, middle) in alone.items():
        print(f"| {label} | {least:.0f} | {middle:.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
