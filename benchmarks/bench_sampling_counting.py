"""A sampled slave's step with its per-step sub-step counting in Python or through ctypes.

    python benchmarks/bench_sampling_counting.py

A Derivator slave (pythonfmu, no FMI layer) steps at h = T / 4 (one sample, three holds a
period); its :meth:`fmus.slave.sampling.SampledSteps.step` counts with Python's integer
comparisons, or with the kernels' ``pc_sampling_samples`` and ``pc_sampling_next`` through
ctypes (the same rule).  Side by side in one run, alternating, 3 rounds of best-of-5 timings
of 20 000 steps; printed: the best µs per step of each and their ratio.  This is why
fmus/slave/sampling.py keeps the per-step comparisons in Python.
"""
import ctypes
import tempfile
import timeit

import kernels
from fmus.slave import sampling
from fmus.slaves.parcosim_derivator import Derivator

_d = ctypes.c_double
_SAMPLES = kernels.function("pc_sampling_samples", ctypes.c_int, _d, _d)
_NEXT = kernels.function("pc_sampling_next", _d, _d, _d)
STEPS = 20000


def ctypes_step(self, current_time, step_size):
    k = self._substep
    if _SAMPLES(k, self.sample_phase):
        self.sample(current_time, step_size)
    else:
        self.between_samples(current_time, step_size)
    self._substep = int(_NEXT(k, self._substeps))


def us_per_step(step) -> float:
    sampling.SampledSteps.step = step
    slave = Derivator(instance_name="bench", resources=tempfile.mkdtemp())
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    h, t = 2.5e-4, [0.0]

    def one():
        slave.do_step(t[0], h)
        t[0] += h
    return min(timeit.repeat(one, number=STEPS, repeat=5)) / STEPS * 1e6


def main():
    python_step = sampling.SampledSteps.step
    best = {"python": [], "ctypes": []}
    for _ in range(3):
        best["python"].append(us_per_step(python_step))
        best["ctypes"].append(us_per_step(ctypes_step))
    sampling.SampledSteps.step = python_step
    p, c = min(best["python"]), min(best["ctypes"])
    print(f"Derivator do_step at h = T/4: Python counting {p:.2f} us, ctypes counting {c:.2f} us, ratio {c / p:.2f}")


if __name__ == "__main__":
    main()
