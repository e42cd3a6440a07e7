"""benchmarks/machine_probe.py: which rounds ran with the machine at full speed (no timing asserted)."""
import pytest

from benchmarks.machine_probe import Probe, quiet_rounds, spread


def test_a_round_counts_only_when_both_probes_are_fast():
    """Catches a round kept when only one of its probes (before or after) was at full speed, a
    tolerance applied the wrong way round, or a reference other than the fastest probe."""
    probes = [(2.0, 2.1), (2.0, 3.6), (3.5, 2.0), (2.29, 2.3), (2.31, 2.0), (3.6, 3.6)]
    assert quiet_rounds(probes, tolerance=1.15) == [0, 3]
    assert quiet_rounds(probes, tolerance=2.0) == [0, 1, 2, 3, 4, 5]
    assert quiet_rounds(probes, tolerance=1.15, fastest_s=1.0) == []
    assert quiet_rounds([]) == []


def test_spread_reads_the_probes():
    """Catches a spread taken over one side of the probes only."""
    s = spread([(2.0, 3.0), (4.0, 2.5)])
    assert (s["fastest_s"], s["median_s"], s["slowest_s"], s["ratio"]) == (2.0, 2.75, 4.0, 2.0)


def test_probe_times_a_workload_that_scales_with_its_sweeps():
    """Catches a probe whose workload is optimised away or does not depend on its sweeps (its time
    would then say nothing about the machine): ten times the sweeps take clearly longer."""
    small, large = Probe(sweeps=200), Probe(sweeps=20000)
    assert min(large() for _ in range(3)) > 5 * min(small() for _ in range(3))
