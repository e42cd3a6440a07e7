"""scenarios/batch/regression.py's own machinery without its 21 long runs (``run_scene`` or
``measure`` replaced by made-up values): the start offset moves every x0 and nothing else, a
run's NaN metric is stored as None and a stopped run refused naming it, ``--write`` stores
exactly what was measured with the commit, ``--sensitivity`` is the largest relative change
computed here, and the command's exit status and lines (issue 31: the scenarios' weakest area;
every stored value read back)."""
from __future__ import annotations

import json
import math
import subprocess
from types import SimpleNamespace

import pytest

from scenarios.batch import regression
from scenarios.scenes.catalogue import get_scene

STORED = {"scene_a": {"e_ef_mm": 1.0, "tau_ef_Nm": 2.0, "e_ss_mm": None, "e_ss_1s_mm": 3.0, "t_settle_s": 0.0,
                      "e_max_mm": 5.0},
          "scene_b": {"e_ef_mm": 4.0, "tau_ef_Nm": 8.0, "e_ss_mm": 0.5, "e_ss_1s_mm": 0.25, "t_settle_s": 2.0,
                      "e_max_mm": 1.0}}


@pytest.fixture
def made_up(monkeypatch):
    monkeypatch.setattr(regression, "regression_scenes", lambda: list(STORED))
    monkeypatch.setattr(regression, "load", lambda: {"scenes": STORED})


def test_the_start_offset_moves_every_x0_and_nothing_else():
    """Catches an offset given to another parameter, to one component only, or subtracted."""
    scene = get_scene("bench_circle_PDq")
    moved = regression._start_offset(scene, 1e-12)
    found = 0
    for before, after in zip(scene.system.components, moved.system.components):
        expected = dict(before.parameters)
        if "x0" in expected:
            expected["x0"] = before.parameters["x0"] + 1e-12
            found += 1
        assert after.parameters == expected and after.name == before.name
    assert found >= 1 and moved.system.connections == scene.system.connections


def test_a_run_is_stored_with_none_for_a_nan_and_a_stopped_run_is_refused_naming_it(monkeypatch):
    """Catches a NaN stored (JSON has none), a finite value changed, the start offset not
    passed to the scene, and a stopped run's metrics stored as if it had run."""
    seen = []
    metrics = {"e_ef_mm": 0.125, "tau_ef_Nm": 1.5, "e_ss_mm": math.nan, "e_ss_1s_mm": 0.0, "t_settle_s": math.inf,
               "e_max_mm": 2.0, "other": 7.0}

    def run_scene(scene, plots=True):
        seen.append((scene, plots))
        return SimpleNamespace(result=SimpleNamespace(error=error), metrics=metrics)

    monkeypatch.setattr(regression, "run_scene", run_scene)
    error = None
    assert regression.measure("bench_circle_PDq", 2e-12) == {
        "e_ef_mm": 0.125, "tau_ef_Nm": 1.5, "e_ss_mm": None, "e_ss_1s_mm": 0.0, "t_settle_s": None, "e_max_mm": 2.0}
    scene, plots = seen[0]
    start = next(c for c in get_scene("bench_circle_PDq").system.components if "x0" in c.parameters)
    assert plots is False and dict(scene.system.components[[c.name for c in scene.system.components].index(
        start.name)].parameters)["x0"] == start.parameters["x0"] + 2e-12
    error = "plant: refused at t = 0.5 s"
    with pytest.raises(RuntimeError, match=r"^bench_circle_PDq: plant: refused at t = 0.5 s$"):
        regression.measure("bench_circle_PDq")


def test_write_stores_each_scenes_measured_metrics_and_the_commit(monkeypatch, tmp_path, made_up):
    """Catches a scene missing, a metric of another scene, the commit not the tree's, and the file
    not in its form (indented JSON ending with a newline, as git and the docs' tools expect)."""
    path = tmp_path / "data" / "scene_metrics.json"
    monkeypatch.setattr(regression, "STORED", path)
    monkeypatch.setattr(regression, "measure", lambda name: {**STORED[name], "e_ef_mm": len(name) + 0.5})
    data = regression.write()
    back = json.loads(path.read_text())
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=regression.ROOT, capture_output=True,
                          text=True).stdout.strip()
    assert back == data and back["commit"] == head and len(head) >= 7
    assert path.read_text() == json.dumps(data, indent=1) + "\n"         # one line per value, a final newline
    assert back["scenes"] == {name: {**values, "e_ef_mm": len(name) + 0.5} for name, values in STORED.items()}


def test_sensitivity_is_the_largest_relative_change_of_a_stored_nonzero_metric(monkeypatch, made_up, capsys):
    """Made up here: scene_b's e_max_mm halved is the largest relative change (0.5);
    None and 0 stored values are skipped.  Catches a change relative to the moved value, an
    absolute change, the offset not passed, and a stored 0 divided by."""
    offsets = []

    def measure(name, dx=0.0):
        offsets.append(dx)
        moved = dict(STORED[name])
        moved["e_ef_mm"] = moved["e_ef_mm"] * (1 + 1e-10)
        if name == "scene_b":
            moved["e_max_mm"] = 0.5                             # |change| / stored = 0.5 (/ moved: 1)
            moved["tau_ef_Nm"] = 8.0 + 8e-9                     # 1e-9 relative, 8e-9 absolute
        else:
            moved["t_settle_s"] = 1.0                           # stored 0: skipped
        return moved

    monkeypatch.setattr(regression, "measure", measure)
    assert regression.sensitivity(5e-12) == 0.5
    assert offsets == [5e-12, 5e-12]
    printed = capsys.readouterr().out.splitlines()
    assert len(printed) == 4 + 6 and f"{'scene_b':24s} {'e_max_mm':10s} 5.00e-01" in printed


def test_the_command_says_all_match_or_names_each_problem_with_its_exit_status(monkeypatch, made_up, capsys):
    """Catches the exit status of a failed comparison 0, and the count of scenes wrong."""
    monkeypatch.setattr(regression, "measure", lambda name: dict(STORED[name]))
    assert regression.main([]) == 0 and capsys.readouterr().out == "all 2 scenes match\n"
    monkeypatch.setattr(regression, "measure", lambda name: {**STORED[name], "e_ss_mm": 0.75})
    assert regression.main([]) == 1
    assert capsys.readouterr().out.splitlines() == ["scene_a e_ss_mm: 0.75, stored None",
                                                    "scene_b e_ss_mm: 0.75, stored 0.5"]


def test_write_and_sensitivity_options_take_effect_and_print_what_they_computed(monkeypatch, made_up, capsys,
                                                                                 tmp_path):
    """``--write`` stores, prints one ``name metrics`` line per scene and returns 0 without
    comparing; ``--sensitivity`` prints the largest change in the documented format and
    returns 0.  Catches an option not reaching its branch (the comparison run instead), the
    printed line's name and metrics swapped or another scene's, and a wrong exit status; the
    stored file's missing folders made (sibling of seed 4201 [196])."""
    monkeypatch.setattr(regression, "STORED", tmp_path / "new" / "stored" / "metrics.json")
    measured = {name: {**values, "e_ef_mm": 10.0 + k} for k, (name, values) in enumerate(STORED.items())}
    monkeypatch.setattr(regression, "measure", lambda name, dx=0.0: dict(measured[name]))
    monkeypatch.setattr(regression, "compare", lambda: pytest.fail("--write ran the comparison"))
    assert regression.main(["--write"]) == 0
    assert capsys.readouterr().out.splitlines() == [f"{name} {measured[name]}" for name in STORED]
    assert json.loads((tmp_path / "new" / "stored" / "metrics.json").read_text())["scenes"] == measured
    monkeypatch.setattr(regression, "load", lambda: {"scenes": STORED})
    monkeypatch.setattr(regression, "sensitivity", lambda: 3.25e-7)
    assert regression.main(["--sensitivity"]) == 0
    assert capsys.readouterr().out == "largest relative change: 3.25e-07\n"


def test_a_metric_off_by_exactly_the_tolerance_passes_and_the_next_float_beyond_is_named(monkeypatch, made_up):
    """"More than the tolerance" (``compare``'s docstring), hit exactly: with the tolerance a
    power of two (2^-20, set here) the boundary values b (1 +- 2^-20) are exact floats, so a
    metric exactly that far off, above or below, passes and one a float farther is named.
    Catches ``>=`` for ``>`` (training seed 4431's boundary sibling of [15])."""
    monkeypatch.setattr(regression, "RELATIVE_TOLERANCE", 0.5 ** 20)
    b = STORED["scene_b"]
    edge = {"e_ef_mm": b["e_ef_mm"] * (1 + 0.5 ** 20), "tau_ef_Nm": b["tau_ef_Nm"] * (1 - 0.5 ** 20)}
    assert all(abs(edge[k] - b[k]) == 0.5 ** 20 * abs(b[k]) for k in edge)      # the boundary, exactly
    beyond = {"e_ef_mm": math.nextafter(edge["e_ef_mm"], math.inf),
              "tau_ef_Nm": math.nextafter(edge["tau_ef_Nm"], -math.inf)}
    monkeypatch.setattr(regression, "measure", lambda name: {**STORED[name], **(edge if name == "scene_b" else {})})
    assert regression.compare() == []
    monkeypatch.setattr(regression, "measure", lambda name: {**STORED[name], **(beyond if name == "scene_b" else {})})
    assert regression.compare() == [f"scene_b e_ef_mm: {beyond['e_ef_mm']!r}, stored 4.0",
                                    f"scene_b tau_ef_Nm: {beyond['tau_ef_Nm']!r}, stored 8.0"]
