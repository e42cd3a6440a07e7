"""How the compiled loop walks a run (fmus/cosim/compiled.py ``run_compiled``): windows of
steps handed to C one after another, a declined step finished in Python, progress after each.

The C loop is watched (``Plan.run`` wrapped): every window must start where the last run
stopped and reach further, so that a window that does not advance fails here at once
instead of hanging the run; together the windows and the Python steps take each step of
[0, steps) exactly once, and the progress reported is what was done over what there is.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim import compiled
from fmus.cosim.master import simulate
from scenarios.scenes.catalogue import get_scene


@pytest.fixture
def windows(monkeypatch):
    """The (k0, k1, where C stopped) of every window the compiled loop runs."""
    seen = []
    original = compiled.Plan.run

    def watched(self, values, record, k0, k1, t0, h):
        assert k0 == (seen[-1][2] + (seen[-1][3] >= 0) if seen else 0), f"window from {k0} after {seen[-1:]}"
        assert k1 > k0, f"a window [{k0}, {k1}) that does not advance (after {seen[-1:]})"
        stop = original(self, values, record, k0, k1, t0, h)
        seen.append((k0, k1, stop.step, stop.member))
        return stop

    monkeypatch.setattr(compiled.Plan, "run", watched)
    return seen


def _scene(name: str, stop_time: float, **ctrl):
    scene = get_scene(name)
    components = tuple(replace(c, parameters={**c.parameters, **ctrl}) if c.name == "ctrl" else c
                       for c in scene.system.components)
    return replace(scene.system, stop_time=stop_time, components=components)


def test_the_windows_tile_the_run_and_progress_is_steps_done_over_steps(windows):
    """Catches a window that does not advance (the run hangs), a window that skips or repeats
    steps, a chunk other than a hundredth of the run, and progress that is not done / steps."""
    system = _scene("bench_circle_TCMDx", 0.35)
    reported = []
    result = simulate(system, mode="compiled", progress=reported.append)
    steps = system.steps
    assert result.error is None and result.mode == "compiled" and result.extra["python_steps"] == 0
    chunk = max(1, steps // 100)
    expected = [(k, min(steps, k + chunk)) for k in range(0, steps, chunk)]
    assert [(k0, k1) for k0, k1, _, _ in windows] == expected
    assert all(stop == k1 for _, k1, stop, _ in windows)
    assert reported == [k1 / steps for _, k1 in expected]
    assert len(result.time) == steps + 1 and not np.isnan(result["plant.x"]).any()


def test_a_step_declined_by_c_is_taken_once_by_python_and_the_next_window_starts_after_it(windows):
    """The controller's table covers only x <= 0.02 m: its samples past that are declined by
    the kernel and finished in Python.  Catches a declined step taken twice or skipped, and a
    window restarted at the declined step."""
    system = _scene("bench_circle_TCx", 0.6, x_max=0.02)
    result = simulate(system, mode="compiled")
    steps = system.steps
    assert result.error is None and 0 < result.extra["python_steps"]
    declined = [stop for _, _, stop, member in windows if member >= 0]
    assert len(declined) == result.extra["python_steps"]
    c_steps = sum(stop - k0 for k0, _, stop, _ in windows)
    assert c_steps + len(declined) == steps
    assert len(result.time) == steps + 1 and not np.isnan(result["plant.x"]).any()
