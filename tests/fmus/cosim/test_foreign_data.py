"""fmus/cosim/foreign.py on systems and FMU files written here (its runs of real foreign FMUs are of
the slow kind): a replacement keeps the component's name, parameters and connections and
resolves the path; bad replacements refused naming the instance or the file; the parameters a
foreign FMU does not have are dropped and listed, from that component only; an SSP's models named
by the files' identifiers, one file per identifier (issue 31: "fmus other"; every value read
back exactly)."""
from __future__ import annotations

import os
import zipfile
from dataclasses import replace

import pytest

from fmus.cosim.foreign import (foreign_components, is_fmu_file, named_models, replace_components,
                                without_missing_parameters)
from scenarios.scenes import get_scene


def _fmu(path, identifier, variables=("u", "y", "k")):
    """A minimal FMI 2.0 co-simulation FMU description (no binary: only read, never run)."""
    scalars = "".join(f'<ScalarVariable name="{n}" valueReference="{k}" causality="parameter" variability="fixed">'
                      f'<Real start="0"/></ScalarVariable>' for k, n in enumerate(variables))
    xml = (f'<?xml version="1.0" encoding="UTF-8"?><fmiModelDescription fmiVersion="2.0" modelName="{identifier}" '
           f'guid="{{g}}" numberOfEventIndicators="0"><CoSimulation modelIdentifier="{identifier}"/>'
           f'<ModelVariables>{scalars}</ModelVariables><ModelStructure/></fmiModelDescription>')
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("modelDescription.xml", xml)
    return path


def test_a_replacement_keeps_the_component_and_resolves_the_path(tmp_path, monkeypatch):
    """Catches the name, parameters, sub-steps or connections lost, a relative path kept (the
    run may change folder), the other components touched, and a case-sensitive '.fmu'."""
    system = get_scene("bench_circle_PDq").system
    (tmp_path / "Drive.FMU").write_bytes(b"")
    monkeypatch.chdir(tmp_path)
    swapped = replace_components(system, {"drive2": "Drive.FMU"})
    for before, after in zip(system.components, swapped.components):
        if before.name == "drive2":
            assert after == replace(before, model=str(tmp_path / "Drive.FMU"))
            assert os.path.isabs(after.model) and is_fmu_file(after.model)
        else:
            assert after == before
    assert swapped.connections == system.connections
    assert foreign_components(swapped) == [f"drive2 ({tmp_path / 'Drive.FMU'})"]
    assert foreign_components(system) == []


def test_bad_replacements_are_refused_naming_the_instance_or_the_file(tmp_path):
    """Catches an unknown instance accepted, a missing file or another extension accepted."""
    system = get_scene("bench_circle_PDq").system
    names = ", ".join(c.name for c in system.components)
    with pytest.raises(ValueError, match=rf"^--replace drive9=\.\.\.: no instance 'drive9'; instances: {names}$"):
        replace_components(system, {"drive9": "x.fmu"})
    (tmp_path / "drive.zip").write_bytes(b"")
    for path in (tmp_path / "missing.fmu", tmp_path / "drive.zip", tmp_path):
        with pytest.raises(ValueError, match=r"^--replace drive1=.*: not an existing \.fmu file$"):
            replace_components(system, {"drive1": str(path)})


def test_parameters_a_foreign_fmu_lacks_are_dropped_from_it_alone_and_listed(tmp_path):
    """drive1 is a foreign FMU with only ``preset`` of the scene's drive parameters; drive2, ours,
    keeps every parameter even those drive1's FMU lacks.  Catches our components' parameters
    dropped, a parameter the FMU has dropped, and the line without the file or the names."""
    system = get_scene("bench_circle_PDq").system
    _fmu(tmp_path / "c_drive.fmu", "CDrive")
    swapped = replace_components(system, {"drive1": str(tmp_path / "c_drive.fmu")})
    drive1 = swapped.component("drive1").parameters
    variables = {c.name: set() for c in swapped.components} | {"drive1": {"preset", "k"}}
    kept, line = without_missing_parameters(swapped, variables)
    missing = [n for n in drive1 if n != "preset"]
    assert missing and kept.component("drive1").parameters == {"preset": drive1["preset"]}
    assert line == f"parameters the foreign FMUs do not have are skipped: drive1 (c_drive.fmu): {', '.join(missing)}"
    for c in swapped.components:
        if c.name != "drive1":
            assert kept.component(c.name) == c
    assert without_missing_parameters(system, {c.name: set() for c in system.components}) == (system, "")


def test_named_models_name_each_file_by_its_identifier_once(tmp_path):
    """Two drives given one file: one model, one file; a second file of the same identifier is
    refused naming both.  Catches the identifier not the file's, the file map of another path,
    and a warning of skipped parameters lost."""
    system = get_scene("bench_circle_PDq").system
    one = str(_fmu(tmp_path / "a.fmu", "CDrive", variables=("preset",)))
    swapped = replace_components(system, {"drive1": one, "drive2": one})
    with pytest.warns(UserWarning, match=r"^parameters the foreign FMUs do not have are skipped: drive1 \(a\.fmu\): "):
        named, files = named_models(swapped)
    assert files == {"CDrive": one}
    assert named.component("drive1").model == named.component("drive2").model == "CDrive"
    assert named.component("drive1").parameters == {"preset": swapped.component("drive1").parameters["preset"]}
    assert named.component("plant") == system.component("plant")
    other = str(_fmu(tmp_path / "b.fmu", "CDrive", variables=("preset",)))
    twice = replace_components(system, {"drive1": one, "drive2": other})
    with pytest.warns(UserWarning), pytest.raises(
            ValueError, match=rf"^component drive2: {other} and {one} are both model 'CDrive'; an SSP package "):
        named_models(twice)
