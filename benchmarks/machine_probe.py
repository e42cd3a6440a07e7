"""How fast the machine is right now: a fixed C workload timed before and after each round.

On this machine (2 vCPUs of a shared host) the same code runs at two speeds that alternate
every few seconds: a fixed C loop that touches nothing of ours takes 2.0 ms in one and
3.6 ms in the other, and the compiled closed loop of bench_circle_TCMDx 8.7 ms or 13.3 ms
with it (docs/benchmarks.md, "The machine's two speeds").  The load average does not see it
(it comes from outside the virtual machine), nor does the thread's CPU time.  A round
between two probes at the run's fastest is a round on the machine at full speed.

    probe = Probe()              # builds machine_probe.c with the kernels' compiler
    before = probe()             # seconds of the fixed workload
    ...                          # the round
    after = probe()
    full = quiet_rounds([(before, after), ...])   # which rounds ran at full speed
"""
from __future__ import annotations

import ctypes
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

from kernels import build

#: Sweeps of the probe: about 2 ms at full speed here.
SWEEPS = 5000
#: A probe within this factor of the run's fastest counts as full speed.
TOLERANCE = 1.15


class Probe:
    """``machine_probe.c`` built into a temporary folder (removed once loaded); calling it times
    one workload."""

    def __init__(self, sweeps: int = SWEEPS):
        self.sweeps = sweeps
        with tempfile.TemporaryDirectory(prefix="parcosim_probe_") as folder:   # loaded, the file may go
            out = Path(folder) / "machine_probe.so"
            subprocess.run([build.compiler(), "-std=c11", "-O2", "-fPIC", "-shared",
                            str(Path(__file__).with_name("machine_probe.c")), "-o", str(out), "-lm"], check=True)
            self._lib = ctypes.CDLL(str(out))
        self._lib.machine_probe.restype = ctypes.c_double
        self._lib.machine_probe.argtypes = [ctypes.c_int]
        self()   # the first call pages the code in

    def __call__(self) -> float:
        """Seconds of one workload (wall clock)."""
        start = time.perf_counter()
        self._lib.machine_probe(self.sweeps)
        return time.perf_counter() - start


def quiet_rounds(probes, tolerance: float = TOLERANCE, fastest_s: float | None = None) -> list:
    """Indices of the rounds whose probes before and after are both within ``tolerance`` of
    ``fastest_s`` (default: the fastest probe of them all; ``probes``: (before, after) seconds
    per round)."""
    if not probes:
        return []
    fastest = fastest_s if fastest_s is not None else min(min(p) for p in probes)
    return [i for i, p in enumerate(probes) if max(p) <= tolerance * fastest]


def spread(probes) -> dict:
    """The probes' fastest, median and slowest seconds, and slowest / fastest."""
    flat = [s for p in probes for s in p]
    return {"fastest_s": min(flat), "median_s": statistics.median(flat), "slowest_s": max(flat),
            "ratio": max(flat) / min(flat)}
