"""The exported packages in other people's tools, used plainly: fmpy's simulate_ssp, Ecos,
libcosim.  What is checked is what the user sees, the tracking: the RMS end-effector error
over [1, 2] s and the RMS torque of a 2 s copy of each scene, against ``parcosim run``.

The package (scenarios.packaging.chain) models one thing differently from our master: the drives
integrated in the plant instead of separate (docs/actuated.md: 6.5e-6 m RMS apart over the
bench circle); the ratio is then 1 within 0.2 % on these scenes (docs/ssp.md).  The
bound asserted, 5 %, is the issue's goal.  The per-component package in the tools:
tests/scenarios/packaging/test_swap_drive.py.
"""
from __future__ import annotations

import dataclasses

import pytest

from scenarios.scenes.catalogue import get_scene
from scenarios.studies.tools import compare, short
from tests.support.tools import UNAVAILABLE

pytestmark = [pytest.mark.slow, pytest.mark.fmu, pytest.mark.tools]

SCENES = ("thesis_sim_circle", "bench_circle_TCMDx", "bench_circle_PDq", "bench_triangle_TCMDx")
STOP = 2.0

TOOLS = tuple(t for t, reason in UNAVAILABLE.items() if reason is None)


@pytest.fixture(scope="module", params=SCENES)
def compared(request, tmp_path_factory):
    scene = dataclasses.replace(short(get_scene(request.param), STOP), window=(1.0, STOP))
    return scene, compare(scene, TOOLS, isolated=False, out_dir=tmp_path_factory.mktemp("pkg"))


@pytest.mark.parametrize("tool", ("fmpy", "ecos", "libcosim"))
def test_the_package_tracks_in_the_tool_as_in_our_master(compared, tool):
    """Catches a package that a tool runs otherwise than our master (another parameter set, initial
    outputs, step): e_ef or tau_ef more than 5 % off."""
    if UNAVAILABLE[tool] is not None:
        pytest.skip(f"{tool} cannot be loaded here: {UNAVAILABLE[tool]}")
    scene, rows = compared
    (_, m, ours, error), = [r for r in rows if r[0] == tool]
    assert m is not None and error is None and m["completed"], error
    assert 0.95 <= m["e_ef_mm"] / ours["e_ef_mm"] <= 1.05, (m["e_ef_mm"], ours["e_ef_mm"])
    assert 0.95 <= m["tau_ef_Nm"] / ours["tau_ef_Nm"] <= 1.05, (m["tau_ef_Nm"], ours["tau_ef_Nm"])


# --- the measurement's bookkeeping (no tool runs) ----------------------------------------------

def test_a_stored_run_is_not_run_again_and_a_new_one_is_merged(tmp_path, monkeypatch):
    """Catches the tools study running again what it stored, or overwriting a run another process stored
    meanwhile."""
    import json

    import scenarios.studies.tools as tools

    metrics = {"e_ef_mm": 1.0, "tau_ef_Nm": 2.0, "simulated_s": 3.0, "completed": True, "cpu_s": 3.0, "step": 1e-3}
    ours = {"e_ef_mm": 1.0, "tau_ef_Nm": 2.0}
    stored = {"ours|bench_circle_PDq|parcosim": ours,
              **{f"default|bench_circle_PDq|{t}": {"metrics": metrics, "error": None} for t in ("fmpy", "ecos")}}
    path = tmp_path / "tools.json"
    path.write_text(json.dumps(stored))
    calls = []

    def one_run(scene, todo, **kwargs):
        calls.append(list(todo))
        # another call stores a run meanwhile: the merge keeps it
        tools._store(path, "default|bench_circle_TCx|fmpy", {"metrics": metrics, "error": None})
        return [(t, dict(metrics, e_ef_mm=1.5), ours, None) for t in todo]

    def no_run(*args, **kwargs):
        raise AssertionError("our master was run again")

    monkeypatch.setattr(tools, "compare", one_run)
    monkeypatch.setattr(tools, "run_scene", no_run)
    rows = tools.measure(["bench_circle_PDq"], tools.TOOLS, ["default"], path, progress=lambda _: None)
    assert calls == [["libcosim"]]   # only the run not stored
    assert [r[0] for r in rows[("default", "bench_circle_PDq")]] == list(tools.TOOLS)
    held = tools.load_results(path)
    assert "default|bench_circle_TCx|fmpy" in held and held["default|bench_circle_PDq|libcosim"]["commit"]
    text = tools.table(tools.stored_rows(held))
    assert "| default | bench_circle_PDq | fmpy | 1 | 1 (1) | 1.0000 | 1.0000 | yes | 1000 |" in text
    assert "| default | bench_circle_PDq | libcosim | 1 | 1.5 (1) | 1.5000 | 1.0000 | yes | 1000 |" in text
    tools.measure(["bench_circle_PDq"], tools.TOOLS, ["default"], path, progress=lambda _: None)
    assert calls == [["libcosim"]]   # all stored now: nothing runs


def test_swap_fmus_replaces_only_the_named_member(tmp_path):
    """Catches a swap that changes other members than the named FMU, or silently adds a member the package
    does not have."""
    import zipfile

    from scenarios.studies.tools import swap_fmus

    package, fmu = tmp_path / "p.ssp", tmp_path / "theirs.fmu"
    with zipfile.ZipFile(package, "w") as zf:
        zf.writestr("SystemStructure.ssd", b"<ssd/>")
        zf.writestr("resources/drive1.fmu", b"ours")
        zf.writestr("resources/drive2.fmu", b"ours too")
    fmu.write_bytes(b"theirs")
    out = swap_fmus(package, {"drive1": fmu}, tmp_path / "out.ssp")
    with zipfile.ZipFile(out) as zf:
        assert {n: zf.read(n) for n in zf.namelist()} == {
            "SystemStructure.ssd": b"<ssd/>", "resources/drive1.fmu": b"theirs", "resources/drive2.fmu": b"ours too"}
    with pytest.raises(ValueError, match="resources/plant.fmu"):
        swap_fmus(package, {"plant": fmu}, tmp_path / "bad.ssp")
