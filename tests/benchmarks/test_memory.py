"""Many runs in one process do not grow its memory (benchmarks/memory_loop.py runs 1000)."""
import sys
from dataclasses import replace

import pytest

from tests.support.paths import ROOT

sys.path.insert(0, str(ROOT / "benchmarks"))

from memory_loop import loop  # noqa: E402

from scenarios.scenes.catalogue import get_scene  # noqa: E402

pytestmark = [pytest.mark.slow]

#: Allowed growth of the resident set over the measured runs [MB]: one run's slaves, table and
#: arrays are about 1 MB, so keeping each run's objects alive would exceed it.
BOUND_MB = 3.0


@pytest.mark.parametrize("mode", ["inprocess", "compiled"])
def test_repeated_runs_do_not_grow_the_resident_set(mode):
    """Catches a leak per run (instances, kernel buffers, compiled plans kept alive) growing the resident
    set past its bound over 30 runs."""
    system = replace(get_scene("bench_circle_TCMDx").system, stop_time=0.02)
    loop(system, mode, 5, 5, report=lambda line: None)          # caches, compilation, allocator pools
    samples = loop(system, mode, 30, 5, report=lambda line: None)
    growth = samples[-1][1] - samples[0][1]
    assert growth < BOUND_MB, f"RSS grew {growth:.1f} MB over {samples[-1][0] - samples[0][0]} runs: {samples}"
