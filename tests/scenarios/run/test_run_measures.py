"""What `parcosim run` measures of itself: the real-time factors and the peak memory
(:func:`scenarios.run.runner.run_scene`, :func:`scenarios.run.runner.peak_rss_mb`)."""
from __future__ import annotations

import resource
import sys
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import pytest

from scenarios.run import runner
from scenarios.scenes.catalogue import get_scene


def test_the_real_time_factors_are_simulated_time_over_wall_and_cpu_time():
    """realtime_factor = simulated_s / wall_s and realtime_factor_cpu = simulated_s / cpu_s, with
    simulated_s the scene's 0.05 s.  Catches a factor that is not a ratio (the simulated time
    alone) or divides by the other clock."""
    scene = get_scene("thesis_sim_circle")
    scene = replace(scene, system=replace(scene.system, stop_time=0.05), window=(0.0, 0.05))
    m = runner.run_scene(scene, mode="inprocess").metrics
    assert m["simulated_s"] == pytest.approx(0.05, abs=1e-12)
    assert m["cpu_s"] > 0.0 and m["wall_s"] > 0.0
    assert m["realtime_factor_cpu"] == pytest.approx(m["simulated_s"] / m["cpu_s"], rel=1e-12)
    assert m["realtime_factor"] == pytest.approx(m["simulated_s"] / m["wall_s"], rel=1e-12)


@pytest.mark.parametrize("platform, maxrss, mb", [("linux", 3 * 1024, 3.0), ("darwin", 5 * 1024 * 1024, 5.0)])
def test_peak_memory_is_in_megabytes_whatever_unit_the_platform_reports(monkeypatch, platform, maxrss, mb):
    """getrusage's ru_maxrss is KiB on Linux and bytes on macOS: both give MB.  Catches a unit
    conversion off by 1024 on either platform."""
    monkeypatch.setattr(sys, "platform", platform)
    monkeypatch.setattr(resource, "getrusage", lambda who: SimpleNamespace(ru_maxrss=maxrss))
    assert runner.peak_rss_mb() == mb


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux's /proc")
def test_peak_memory_is_the_kernels_high_water_mark():
    """On Linux the peak is the kernel's VmHWM of this process (read from /proc, an independent
    source), to 1 MB.  Catches a peak in other units or of another process."""
    high = next(int(line.split()[1]) for line in Path("/proc/self/status").read_text().splitlines()
                if line.startswith("VmHWM:"))
    assert runner.peak_rss_mb() == pytest.approx(high / 1024.0, abs=1.0)
