"""The native FMU's modelDescription.xml as fmus/native/build.py ``model_description`` writes
it, read back by fmpy: the version asked for (2 or 3), the GUID given, the generation tool,
the C sources listed (FMI 2.0) and the ModelStructure from the feedthrough given, without
building an FMU (fast; tests/fmus/native/test_native_build.py builds them).
"""
from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest
from fmpy import read_model_description

from fmus.native.build import model_description
from fmus.slaves.parcosim_derivator import Derivator

GUID = "{0b7d-native-test}"
SOURCES = ["pcn_derivator.c", "derivator.c", "pcn_fmi2.h", "derivator.h"]


def _read(tmp_path, version: int):
    slave = Derivator(instance_name="d")
    feedthrough = {"dq1": (), "dq2": ()}
    xml = model_description(slave, "Derivator", GUID, SOURCES, feedthrough, fmi_version=version, time_vr=9999)
    path = tmp_path / f"md{version}.xml"
    path.write_bytes(xml)
    return xml, read_model_description(str(path), validate=version == 3)


def test_fmi2_is_written_when_asked_with_the_guid_sources_and_structure(tmp_path):
    """Catches the version choice inverted (FMI 3.0 written for 2), the GUID or the tool not
    set, a header listed as a source, and the pythonfmu ModelStructure kept."""
    xml, md = _read(tmp_path, 2)
    assert md.fmiVersion == "2.0" and md.guid == GUID
    assert md.generationTool == "parcosim native (fmus/native)"
    listed = ET.fromstring(xml).find("CoSimulation").find("SourceFiles")
    assert [f.get("name") for f in listed] == ["pcn_derivator.c", "derivator.c"]
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    assert not md.coSimulation.needsExecutionTool
    assert {"dq1", "dq2"} <= {u.variable.name for u in md.outputs}
    assert all(u.dependencies == [] for u in md.outputs if u.variable.name in ("dq1", "dq2"))
    assert xml.count(b"<ModelStructure>") == 1


def test_fmi3_is_written_when_asked_with_time_at_its_reference(tmp_path):
    """Catches FMI 2.0 written for 3, and the instantiation token or time's value reference lost."""
    _, md = _read(tmp_path, 3)
    assert md.fmiVersion == "3.0" and md.guid == GUID
    time = [v for v in md.modelVariables if v.causality == "independent"]
    assert [(v.name, v.valueReference) for v in time] == [("time", 9999)]


@pytest.mark.parametrize("version", [2, 3])
def test_every_variable_of_the_slave_is_described_once(tmp_path, version):
    """Catches variables dropped or doubled between the slave and its native description."""
    _, md = _read(tmp_path, version)
    names = [v.name for v in md.modelVariables if v.causality != "independent"]
    assert sorted(names) == sorted(v.name for v in Derivator(instance_name="d").vars.values())


@pytest.mark.parametrize("model", ["Trajectory", "Derivator", "DCMotorDrive"])
def test_the_slave_a_build_reads_is_initialised_at_time_zero_with_its_start_values(model, tmp_path):
    """The data and start values a native FMU carries come from its slave initialised at
    t = 0 (fmus/native/build.py ``initialised_slave``).  Catches another start time (the
    trajectory's first point would be another) and the slave's state not that of a slave set
    up by hand at 0."""
    import importlib

    from fmus.native.build import initialised_slave
    from fmus.slave.registry import SLAVES

    built = initialised_slave(model, tmp_path)
    by_hand = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)(instance_name=model)
    by_hand.setup_experiment(0.0)
    by_hand.enter_initialization_mode()
    by_hand.exit_initialization_mode()
    assert built._start_time == 0.0 and built.error == ""
    outputs = [v.name for v in by_hand.vars.values() if v.causality is not None and v.causality.name == "output"]
    assert {n: getattr(built, n) for n in outputs} == {n: getattr(by_hand, n) for n in outputs}
