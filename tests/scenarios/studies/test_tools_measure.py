"""scenarios/studies/tools.py's ``measure`` (the tools study's driver) without a tool run: the
comparison, our master's run, the export's trial and the C drive's build replaced by ones that
record what they are given.  Held against its docstring: every (kind, scene) asked for is a
row per tool, from the file or new; the kinds that swap or fold the drives skip a scene
without them; our master runs once per scene, the trial once per scene and placement, the C
drive is built once and only for its kinds; each tool run's metrics, error and the trial are
stored and read back exactly; each run's progress line (issue 31: the bookkeeping of a study,
every stored value read back)."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

import scenarios.packaging.per_component as per_component
import scenarios.studies.tools as tools
from fmus.status import RunError, RunStatus

TOOLS = ("fmpy", "ecos")
KINDS = ["default", "per-component+c-drive", "internal-observer", "per-component"]
FAILED = RunError(RunStatus.FAILED, "RuntimeError: ecos stopped", instance="plant", time=0.25)


@pytest.fixture
def fakes(monkeypatch):
    """Our master's e_ef is 2 mm on every scene; a tool's is 2.5 mm (fmpy), ecos fails on
    the per-component kinds; the trial's n is 4 (per-component) or 6 (internal observer)."""
    calls = {"run_scene": [], "compare": [], "trial": [], "c_drive": []}
    clock = [10.0]

    def run_scene(scene, mode):
        calls["run_scene"].append((scene.name, mode))
        return SimpleNamespace(metrics={"e_ef_mm": 2.0, "tau_ef_Nm": 0.5, "scene": scene.name})

    def compare(scene, todo, kind, c_drive, ours, substeps):
        calls["compare"].append((scene.name, list(todo), kind, c_drive, ours, substeps))
        clock[0] += 3.0
        rows = []
        for tool in todo:
            if tool == "ecos" and kind.startswith("per-component"):
                rows.append((tool, None, ours, FAILED))
            else:
                rows.append((tool, {"e_ef_mm": 2.5, "tau_ef_Nm": 0.5, "kind": kind}, ours, None))
        return rows

    def trial(scene, internal_observer):
        calls["trial"].append((scene.name, internal_observer))
        return (6 if internal_observer else 4), {2: (1.25, 1.5), 4: (1.0, 1.0)}, 0.125

    def build_c_drive(where):
        calls["c_drive"].append(where)
        return where / "dcdrive.fmu"

    monkeypatch.setattr(tools, "run_scene", run_scene)
    monkeypatch.setattr(tools, "compare", compare)
    monkeypatch.setattr(tools, "build_c_drive", build_c_drive)
    monkeypatch.setattr(tools, "_commit", lambda: "abc1234")
    monkeypatch.setattr(tools, "_time", SimpleNamespace(perf_counter=lambda: clock[0]))
    monkeypatch.setattr(per_component, "trial", trial)
    return calls


def test_each_kind_runs_what_it_needs_once_and_stores_it(fakes, tmp_path):
    """Catches a drive-swapping or observer kind run on a scene without drives (or a scene with
    drives skipped), our master run again per kind, the trial run for kinds without one, run
    twice or with the other placement, its n not passed on, the C drive built for other kinds
    or per scene, the tools not stored, a failed run's error lost, and the progress line's
    ratio, kind, scene or tool wrong."""
    path = tmp_path / "tools.json"
    said = []
    rows = tools.measure(["thesis_sim_circle", "bench_circle_PDq"], TOOLS, KINDS, path, progress=said.append)
    assert list(rows) == [("default", "thesis_sim_circle"), ("default", "bench_circle_PDq"),
                          ("per-component+c-drive", "bench_circle_PDq"), ("internal-observer", "bench_circle_PDq"),
                          ("per-component", "thesis_sim_circle"), ("per-component", "bench_circle_PDq")]
    assert fakes["run_scene"] == [("thesis_sim_circle", "inprocess"), ("bench_circle_PDq", "inprocess")]
    assert fakes["trial"] == [("bench_circle_PDq", False), ("bench_circle_PDq", True), ("thesis_sim_circle", False)]
    (c_dir,) = fakes["c_drive"]
    assert c_dir.name == "c"
    ours = {"thesis_sim_circle": {"e_ef_mm": 2.0, "tau_ef_Nm": 0.5, "scene": "thesis_sim_circle"},
            "bench_circle_PDq": {"e_ef_mm": 2.0, "tau_ef_Nm": 0.5, "scene": "bench_circle_PDq"}}
    seen = [(scene, todo, kind, c_drive, {k: v for k, v in o.items() if k in ("e_ef_mm", "tau_ef_Nm", "scene")}, n)
            for scene, todo, kind, c_drive, o, n in fakes["compare"]]
    assert seen == [("thesis_sim_circle", list(TOOLS), "default", None, ours["thesis_sim_circle"], None),
                    ("bench_circle_PDq", list(TOOLS), "default", None, ours["bench_circle_PDq"], None),
                    ("bench_circle_PDq", list(TOOLS), "per-component+c-drive", c_dir / "dcdrive.fmu",
                     ours["bench_circle_PDq"], 4),
                    ("bench_circle_PDq", list(TOOLS), "internal-observer", c_dir / "dcdrive.fmu",
                     ours["bench_circle_PDq"], 6),
                    ("thesis_sim_circle", list(TOOLS), "per-component", c_dir / "dcdrive.fmu",
                     ours["thesis_sim_circle"], 4),
                    ("bench_circle_PDq", list(TOOLS), "per-component", c_dir / "dcdrive.fmu",
                     ours["bench_circle_PDq"], 4)]
    assert said[:2] == ["default thesis_sim_circle fmpy: e_ef x1.2500 [3 s]",
                        "default thesis_sim_circle ecos: e_ef x1.2500 [3 s]"]
    assert said[4:6] == ["per-component+c-drive bench_circle_PDq fmpy: e_ef x1.2500 [3 s]",
                         f"per-component+c-drive bench_circle_PDq ecos: failed ({FAILED}) [3 s]"]
    assert len(said) == 2 * len(rows)
    held = tools.load_results(path)
    assert held["trial|bench_circle_PDq|per-component"] == {
        "substeps": 4, "floor": 0.125, "tried": {"2": [1.25, 1.5], "4": [1.0, 1.0]}, "commit": "abc1234",
        "load": held["trial|bench_circle_PDq|per-component"]["load"]}
    assert held["trial|bench_circle_PDq|internal-observer"]["substeps"] == 6
    assert held["ours|bench_circle_PDq|parcosim"]["e_ef_mm"] == 2.0
    assert held["per-component|bench_circle_PDq|ecos"]["error"] == FAILED.record()
    assert held["per-component|bench_circle_PDq|ecos"]["metrics"] is None
    assert held["internal-observer|bench_circle_PDq|fmpy"]["metrics"] == {"e_ef_mm": 2.5, "tau_ef_Nm": 0.5,
                                                                         "kind": "internal-observer"}
    (fmpy, ecos) = rows[("per-component", "bench_circle_PDq")]
    assert fmpy[0] == "fmpy" and fmpy[1]["kind"] == "per-component" and fmpy[3] is None
    assert ecos[0] == "ecos" and ecos[1] is None and ecos[3] == FAILED
    assert fmpy[2]["e_ef_mm"] == 2.0 and fmpy[2]["commit"] == "abc1234"


def test_a_second_call_runs_nothing_and_reads_every_row_back(fakes, tmp_path):
    """Catches a stored run, trial or master run done again, and rows read back otherwise than
    the first call gave them."""
    path = tmp_path / "tools.json"
    first = tools.measure(["bench_circle_PDq"], TOOLS, KINDS, path, progress=lambda _: None)
    for calls in fakes.values():
        calls.clear()
    again = tools.measure(["bench_circle_PDq"], TOOLS, KINDS, path, progress=pytest.fail)
    assert all(calls == [] for calls in fakes.values())
    assert again == first


def test_a_new_tool_runs_alone_with_the_stored_trial_and_master_run(fakes, tmp_path):
    """Catches the tools already stored run again beside a new one, and a stored trial's n
    not the one passed."""
    path = tmp_path / "tools.json"
    tools.measure(["bench_circle_PDq"], ("fmpy",), ["per-component"], path, progress=lambda _: None)
    fakes["compare"].clear()
    fakes["trial"].clear()
    rows = tools.measure(["bench_circle_PDq"], TOOLS, ["per-component"], path, progress=lambda _: None)
    assert [(c[1], c[5]) for c in fakes["compare"]] == [(["ecos"], 4)] and fakes["trial"] == []
    assert [r[0] for r in rows[("per-component", "bench_circle_PDq")]] == list(TOOLS)
    assert fakes["run_scene"] == [("bench_circle_PDq", "inprocess")]


def test_the_c_drive_is_built_once_for_all_scenes_and_the_1ms_kind_has_no_trial(fakes, tmp_path):
    """Catches the C drive built again for each scene, and a trial run (or its n passed) for the
    kind that keeps the 1 ms period."""
    scenes = ["bench_circle_PDq", "bench_triangle_TCx"]
    tools.measure(scenes, TOOLS, ["per-component+c-drive", "internal-observer-1ms"], tmp_path / "t.json",
                  progress=lambda _: None)
    assert len(fakes["c_drive"]) == 1
    assert fakes["trial"] == [(name, False) for name in scenes]
    assert [(c[0], c[2], c[5]) for c in fakes["compare"]] == [
        ("bench_circle_PDq", "per-component+c-drive", 4), ("bench_triangle_TCx", "per-component+c-drive", 4),
        ("bench_circle_PDq", "internal-observer-1ms", None), ("bench_triangle_TCx", "internal-observer-1ms", None)]
