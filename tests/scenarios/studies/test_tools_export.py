"""scenarios/studies/tools.py's ``export_kind`` and ``swap_fmus`` on a short bench scene at a
given sub-step count (the trial and the tools' runs are of the slow kind, test_tools.py): each
kind's file, step, columns and foreign flag, and the C-drive kind's package read back member by
member against the per-component package it was swapped from (issue 31: every written value
read back exactly, options taking effect)."""
from __future__ import annotations

import warnings
import zipfile

import pytest

from scenarios.scenes import get_scene
from scenarios.studies import tools

SCENE = tools.short(get_scene("bench_circle_PDq"), 0.05)
COLUMNS = {"plant.x": "x", "plant.y": "y", "traj.x_d": "x_d", "traj.y_d": "y_d", "ctrl.tau1": "tau1",
           "ctrl.tau2": "tau2"}


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """Each kind but the default at 2 sub-steps, the C drive a file of made-up bytes (the
    swap copies bytes: it never opens the FMU)."""
    out = tmp_path_factory.mktemp("kinds")
    c_drive = out / "c_drive.fmu"
    c_drive.write_bytes(b"a C drive's bytes \x00\xff")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # 2 sub-steps do not track: the export warns, and exports
        kinds = {kind: tools.export_kind(kind, SCENE, out, c_drive=c_drive, substeps=2)
                 for kind in ("per-component+c-drive", "internal-observer-1ms")}
    return out, c_drive, kinds


def _members(path) -> dict:
    with zipfile.ZipFile(path) as z:
        return {i.filename: (z.read(i), i.date_time, i.compress_type) for i in z.infolist()}


def test_the_c_drive_kind_is_the_per_component_package_with_both_drives_replaced(exported):
    """The swapped package beside the one it came from: every member in the same order, with the
    same bytes, date and compression, but resources/drive1.fmu and drive2.fmu, which are the C
    drive's bytes; the step of 2 sub-steps, the metric columns, foreign.  Catches the swap
    written over its source or elsewhere, a drive left out, a member changed or dropped, the
    flag lost."""
    out, c_drive, kinds = exported
    swapped = kinds["per-component+c-drive"]
    source = out / "bench_circle_PDq.per-component+c-drive.ssp"
    assert swapped.path == out / "bench_circle_PDq.per-component+c-drive.swapped.ssp"
    assert (swapped.step, swapped.columns, swapped.foreign) == (SCENE.system.step / 2, COLUMNS, True)
    before, after = _members(source), _members(swapped.path)
    assert list(after) == list(before) and "SystemStructure.ssd" in after
    for name, (data, date, compression) in after.items():
        if name in ("resources/drive1.fmu", "resources/drive2.fmu"):
            assert data == c_drive.read_bytes() != before[name][0], name
            assert (date, compression) == before[name][1:], name
        else:
            assert (data, date, compression) == before[name], name


def test_the_one_millisecond_internal_observer_kind_ignores_the_sub_steps(exported):
    """``internal-observer-1ms``: one sub-step whatever is asked (the step is the scene's), the
    observers inside the drives (no obs1/obs2 FMU), not foreign.  Catches the asked sub-steps
    taken, the observers exported beside the drives."""
    out, _, kinds = exported
    kind = kinds["internal-observer-1ms"]
    assert kind.path == out / "bench_circle_PDq.internal-observer-1ms.ssp"
    assert (kind.step, kind.columns, kind.foreign) == (SCENE.system.step, COLUMNS, False)
    names = set(_members(kind.path))
    assert {"resources/drive1.fmu", "resources/drive2.fmu", "resources/plant.fmu"} <= names
    assert not {"resources/obs1.fmu", "resources/obs2.fmu"} & names


def test_a_swap_of_an_instance_the_package_lacks_is_refused_naming_it(exported, tmp_path):
    """Catches a swap that adds a member the SSD does not bind (or drops the request) instead of
    refusing, and a refusal that names other members."""
    out, c_drive, kinds = exported
    package = kinds["internal-observer-1ms"].path
    with pytest.raises(ValueError) as refusal:
        tools.swap_fmus(package, {"obs1": c_drive, "plant": c_drive, "obs2": c_drive}, tmp_path / "x.ssp")
    assert str(refusal.value) == f"{package} has no resources/obs1.fmu, resources/obs2.fmu"


def test_the_c_drive_is_built_by_its_own_script_even_when_a_module_named_build_was_imported(tmp_path, monkeypatch):
    """A user's process may hold another top-level ``build`` module (PyPA's build, a project's build.py):
    the C drive FMU of the foreign-FMU studies still comes from tests/support/cfmu/build.py, loaded by its
    path.  Catches the script imported by name (the other module taken for it: an ImportError)."""
    import shutil
    import sys
    import types

    if not (shutil.which("cc") or shutil.which("gcc")):
        pytest.skip("no C compiler")
    monkeypatch.setitem(sys.modules, "build", types.ModuleType("build"))
    fmu = tools.build_c_drive(tmp_path)
    with zipfile.ZipFile(fmu) as z:
        assert "modelDescription.xml" in z.namelist() and any(n.endswith(".so") for n in z.namelist())
