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


def test_the_run_figures_draw_the_path_errors_and_torques_in_their_units(tmp_path, monkeypatch):
    """path.png: the reference and the end effector in mm; errors.png: e_x = x_d - x and e_y = y_d - y
    in mm; torques.png: τ1, τ2 in N m; the metric window's edges dotted on every panel.  Catches a
    panel in the wrong unit, an error of the wrong sign or axis, or the window not marked."""
    import matplotlib.pyplot as plt
    import numpy as np

    kept = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    scene = replace(get_scene("bench_circle_PDq"), window=(0.01, 0.03))
    t = np.arange(5) * 0.01
    columns = {"t": t, "x": 0.001 * t, "y": 0.1 + 0.002 * t, "x_d": 0.003 * t, "y_d": 0.1 - t,
               "tau1": 0.5 * t, "tau2": -0.25 * t}
    files = runner.plot_run(scene, columns, tmp_path)
    assert [f.name for f in files] == ["path.png", "errors.png", "torques.png"] and all(f.exists() for f in files)
    reference, effector = kept[0].axes[0].lines
    assert np.allclose(reference.get_xydata(), np.column_stack([1e3 * columns["x_d"], 1e3 * columns["y_d"]]))
    assert np.allclose(effector.get_xydata(), np.column_stack([1e3 * columns["x"], 1e3 * columns["y"]]))
    expected = {1: (1e3 * (columns["x_d"] - columns["x"]), 1e3 * (columns["y_d"] - columns["y"])),
                2: (columns["tau1"], columns["tau2"])}
    for k, (first, second) in expected.items():
        for ax, values in zip(kept[k].axes, (first, second)):
            curve, *edges = ax.lines
            assert np.allclose(curve.get_xdata(), t) and np.allclose(curve.get_ydata(), values, rtol=1e-12, atol=0)
            assert sorted(e.get_xdata()[0] for e in edges) == [0.01, 0.03]


def test_a_results_csv_reads_back_every_double_exactly_and_json_writes_non_finite_as_null(tmp_path):
    """result.csv holds each value to all 17 digits (read back bit for bit) under the columns'
    names; metrics.json writes NaN and inf as null, in nested lists and dicts too, indented, each file
    ending in a newline.  Catches a rounded format, a missing header, a non-finite value written as
    NaN (not JSON) and a last line without its newline."""
    import json

    import numpy as np

    values = {"t": np.array([0.0, 1e-3, 2e-3]), "x": np.array([1 / 3, -2.0 ** -40, 123456.789012345678]),
              "tau1": np.array([np.pi, np.e, 1e-300])}
    runner.write_csv(tmp_path / "result.csv", values)
    lines = (tmp_path / "result.csv").read_text().splitlines()
    assert lines[0] == "t,x,tau1"
    back = np.loadtxt(tmp_path / "result.csv", delimiter=",", skiprows=1)
    assert np.array_equal(back, np.column_stack(list(values.values())))
    runner.write_json(tmp_path / "m.json", {"a": float("nan"), "b": [1.5, float("inf")], "c": {"d": -float("inf")}})
    assert json.loads((tmp_path / "m.json").read_text()) == {"a": None, "b": [1.5, None], "c": {"d": None}}
    # indented by two and ended by a newline (a POSIX text file: `cat`, `diff` and `wc -l` count its
    # last line): the exact text, not only what json reads back (seed 3901 [121])
    assert (tmp_path / "m.json").read_text() == json.dumps({"a": None, "b": [1.5, None], "c": {"d": None}},
                                                           indent=2) + "\n"
    assert (tmp_path / "result.csv").read_text().endswith("\n") and len(lines) == 4


def test_a_failed_write_keeps_the_old_file_leaves_no_temporary_and_names_the_file(tmp_path):
    """atomic_write: an OSError while writing (a full disk) raises WriteError naming the file and
    the reason, with its errno; an interrupt is re-raised; either way the old content stays and
    no temporary file is left.  check_writable names a directory it cannot create.  Catches a
    half-written file, a temporary left behind or a message without the path."""
    import errno

    path = tmp_path / "metrics.json"
    path.write_text("old\n")

    def full(f):
        f.write("new, half")
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(runner.WriteError) as failure:
        runner.atomic_write(path, full)
    assert failure.value.strerror == f"cannot write {path}: No space left on device"
    assert failure.value.errno == errno.ENOSPC

    def interrupted(f):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        runner.atomic_write(path, interrupted)
    assert path.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["metrics.json"]
    assert runner.atomic_write(path, lambda f: f.write("new\n")) == path and path.read_text() == "new\n"
    with pytest.raises(runner.WriteError) as failure:
        runner.check_writable(path / "out")           # under a file: cannot be created
    assert failure.value.strerror.startswith(f"output directory {path / 'out'} is not writable: ")
    assert runner.check_writable(tmp_path / "a" / "b") == tmp_path / "a" / "b" and (tmp_path / "a" / "b").is_dir()


@pytest.mark.parametrize("umask", [0o022, 0o027], ids=["umask-022", "umask-027"])
def test_a_file_written_atomically_has_the_mode_open_would_give_it(tmp_path, umask):
    """atomic_write's temporary file (mkstemp's 0600) is renamed into place with the mode a
    plain ``open(path, "w")`` gives under the same umask (written here beside it), whether the
    file is new or replaced.  Catches results only their owner can read, or the umask
    ignored."""
    import os
    import stat

    old = os.umask(umask)
    try:
        with open(tmp_path / "plain.txt", "w") as f:
            f.write("x\n")
        written = runner.write_json(tmp_path / "m.json", {"a": 1})
        again = runner.write_json(tmp_path / "m.json", {"a": 2})
    finally:
        os.umask(old)
    want = stat.S_IMODE((tmp_path / "plain.txt").stat().st_mode)
    assert want == 0o666 & ~umask
    assert written == again and stat.S_IMODE(again.stat().st_mode) == want
