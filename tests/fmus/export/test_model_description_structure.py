"""fmus/export/modeldescription.py and mark.py on FMU archives written here: the ModelStructure
read back index by index (1-based, each output's direct-feedthrough inputs under Outputs, those
and every parameter under InitialUnknowns, sorted), unknown names refused, the rewritten
archive's other members byte for byte; the build's mark read back and recognised only for its
own model (issue 31: every exported value read back exactly)."""
from __future__ import annotations

import importlib
import json
import zipfile
from xml.etree import ElementTree as ET

import pytest
from pythonfmu.fmi2slave import FMI2_MODEL_OPTIONS

from fmus.export.mark import MARK, built_by_parcosim, mark_file
from fmus.export.modeldescription import fix_model_structure, model_structure
from fmus.slave.identity import IDENTITY_FILE
from fmus.slave.registry import SLAVES

#: (name, causality) of the made-up model's variables, in order: indices 1 to 7.
VARIABLES = [("k", "parameter"), ("u1", "input"), ("y1", "output"), ("u2", "input"), ("y2", "output"),
             ("m", "parameter"), ("y3", "output")]


def _description() -> ET.Element:
    root = ET.Element("fmiModelDescription", fmiVersion="2.0", modelName="Made")
    ET.SubElement(root, "CoSimulation", modelIdentifier="Made")
    variables = ET.SubElement(root, "ModelVariables")
    for name, causality in VARIABLES:
        ET.SubElement(ET.SubElement(variables, "ScalarVariable", name=name, causality=causality), "Real")
    ET.SubElement(root, "ModelStructure")
    ET.SubElement(root, "Annotations")
    return root


def _unknowns(structure, section):
    return [(u.get("index"), u.get("dependencies")) for u in structure.find(section).findall("Unknown")]


def test_each_output_lists_its_feedthrough_inputs_and_with_the_parameters_its_initial_dependencies():
    """y1 depends on u2 then u1 (listed out of order), y2 on nothing, y3 is not listed.
    Catches 0-based indices, unsorted or missing dependencies, parameters left out of the
    initial unknowns or put among the outputs' dependencies, and an input listed as an
    output."""
    structure = model_structure(_description(), {"y1": ("u2", "u1"), "y2": ()})
    assert _unknowns(structure, "Outputs") == [("3", "2 4"), ("5", ""), ("7", "")]
    assert _unknowns(structure, "InitialUnknowns") == [("3", "1 2 4 6"), ("5", "1 6"), ("7", "1 6")]
    with pytest.raises(ValueError, match=r"^feedthrough names unknown variables: \['u9', 'y9'\]$"):
        model_structure(_description(), {"y9": ("u1",), "u9": ()})


def test_the_archive_gets_the_structure_in_place_and_keeps_every_other_member(tmp_path):
    """Catches the structure appended after Annotations (FMI's order), another member changed
    or lost, and the old empty ModelStructure kept beside the new one."""
    fmu = tmp_path / "made.fmu"
    other = {"binaries/linux64/Made.so": b"\x7fELF\x00binary", "resources/data.json": b'{"a": 1}\n'}
    with zipfile.ZipFile(fmu, "w") as z:
        z.writestr("modelDescription.xml", ET.tostring(_description(), encoding="UTF-8", xml_declaration=True))
        for name, data in other.items():
            z.writestr(name, data)
    fix_model_structure(fmu, {"y2": ("u1",)})
    with zipfile.ZipFile(fmu) as z:
        assert sorted(z.namelist()) == sorted(["modelDescription.xml", *other])
        assert all(z.read(name) == data for name, data in other.items())
        root = ET.fromstring(z.read("modelDescription.xml"))
    assert [child.tag for child in root] == ["CoSimulation", "ModelVariables", "ModelStructure", "Annotations"]
    assert _unknowns(root.find("ModelStructure"), "Outputs") == [("3", ""), ("5", "2"), ("7", "")]
    assert [v.get("name") for v in root.find("ModelVariables")] == [n for n, _ in VARIABLES]


def _zip(path, members):
    with zipfile.ZipFile(path, "w") as z:
        for name, data in members.items():
            z.writestr(name, data)
    return path


def test_the_mark_says_which_model_parcosim_built_and_nothing_else_passes(tmp_path):
    """The mark written by ``mark_file`` read back; an FMU is ours for its own model only; an
    FMU from before the mark is recognised by the slave base and its model name; anything else
    (another tool's FMU, a broken mark, no zip, no file) is not ours.  Catches the model not
    compared, a legacy FMU of another model taken, and a broken file raising."""
    mark = mark_file(tmp_path, "Plant", "parcosim_fmu_plant")
    assert mark == tmp_path / IDENTITY_FILE
    assert json.loads(mark.read_text()) == {"model": "Plant", "built_by": "parcosim", "package": "parcosim_fmu_plant"}
    ours = _zip(tmp_path / "ours.fmu", {MARK: mark.read_bytes(), "modelDescription.xml": b"<x/>"})
    assert built_by_parcosim(ours, "Plant") and not built_by_parcosim(ours, "Drive")
    legacy = _zip(tmp_path / "old.fmu", {"resources/fmus/guarded.py": b"",
                                         "modelDescription.xml": b'<fmiModelDescription modelName="Drive"/>'})
    assert built_by_parcosim(legacy, "Drive") and not built_by_parcosim(legacy, "Plant")
    foreign = _zip(tmp_path / "foreign.fmu", {"modelDescription.xml": b'<fmiModelDescription modelName="Drive"/>'})
    broken = _zip(tmp_path / "broken.fmu", {MARK: b"{not json"})
    (tmp_path / "text.fmu").write_text("not a zip")
    for path in (foreign, broken, tmp_path / "text.fmu", tmp_path / "missing.fmu"):
        assert built_by_parcosim(path, "Drive") is False, path.name


@pytest.mark.parametrize("model", ["FiveBarPlant", "DCMotorDrive", "CurrentObserver", "Trajectory", "Derivator",
                                   "PositionController", "ActuatedFiveBarPlant", "WheeledPendulum",
                                   "BalanceController"])
def test_every_slaves_description_takes_the_builds_model_options(model):
    """Each slave's modelDescription (its own ``to_xml``: the plain, sampled and drive ones) writes the
    options the build gives (the state capabilities, the variable step size) on its CoSimulation
    element, and pythonfmu's defaults without them.  Catches options dropped on the way to pythonfmu
    (an FMU that can serialise its state but does not say so to the importer)."""
    cls = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)
    names = ("canGetAndSetFMUstate", "canSerializeFMUstate", "canHandleVariableCommunicationStepSize")
    default = {o.name: str(o.value).lower() for o in FMI2_MODEL_OPTIONS if o.name in names}
    given = {name: "false" if value == "true" else "true" for name, value in default.items()}   # each flipped
    assert len(given) == 3
    cs = cls(instance_name="m").to_xml(given).find("CoSimulation")
    assert {name: cs.get(name) for name in given} == given, model
    plain = cls(instance_name="m").to_xml().find("CoSimulation")
    assert {name: plain.get(name) for name in given} == default, model
