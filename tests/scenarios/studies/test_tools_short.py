"""scenarios/studies/tools.py's helpers that run nothing: a scene shortened for a test, and the
package kinds it refuses (before anything is exported)."""
from __future__ import annotations

import pytest

from scenarios.scenes import get_scene
from scenarios.studies import tools


@pytest.mark.parametrize("stop, window", [(0.5, (0.25, 0.5)), (4.0, (1.0, 4.0)), (9.0, (1.0, 8.0))])
def test_a_shortened_scene_ends_its_system_and_its_metric_window_there(stop, window):
    """bench_circle (11 s, window [1, 8] s) cut at 0.5 s: window [0.25, 0.5] (the start at most half
    the stop); at 4 s [1, 4]; at 9 s [1, 8]; at or past its end (or None) the scene itself.  Catches
    the window's start or end not clipped, or the stop time not applied."""
    scene = get_scene("bench_circle_PDq")
    cut = tools.short(scene, stop)
    assert (cut.system.stop_time, cut.window) == (stop, window)
    assert cut.system.components == scene.system.components and cut.name == scene.name
    assert tools.short(scene, None) is scene and tools.short(scene, 11.0) is scene and tools.short(scene, 12.0) is scene


def test_an_unknown_kind_and_a_drive_swap_without_drives_are_refused_by_name(tmp_path):
    """Catches an unknown package kind exported as some other kind, and the C-drive swap attempted on
    a scene with no drive1/drive2 (thesis_sim_circle) without saying so."""
    with pytest.raises(ValueError) as refusal:
        tools.export_kind("per-instance", get_scene("bench_circle_PDq"), tmp_path)
    assert str(refusal.value) == f"kind = 'per-instance'; valid: {', '.join(tools.KINDS)}"
    with pytest.raises(ValueError, match="scene thesis_sim_circle has no drive1/drive2 to swap"):
        tools.export_kind("per-component+c-drive", tools.short(get_scene("thesis_sim_circle"), 0.01), tmp_path)
    with pytest.raises(ValueError) as refusal:
        tools.run_tool("openmodelica", tmp_path / "x.ssp", [], 0.1, 1e-3)
    assert str(refusal.value) == f"tool = 'openmodelica'; valid: {', '.join(tools.TOOLS)}"
