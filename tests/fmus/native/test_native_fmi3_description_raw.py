"""fmus/native/fmi3xml.py's FMI 3.0 text read back attribute by attribute (issue 31: every
written attribute compared exactly, defaults included), on the FMI 2.0 description of
test_native_fmi3_description.py.  fmpy fills FMI 3.0's defaults in, so a dropped attribute whose
default differs only in the text (or an attribute fmpy does not read) is caught here, not there.
No FMU is built."""
from __future__ import annotations

from xml.etree import ElementTree as ET

from fmus.native.fmi3xml import fmi3_model_description
from tests.fmus.native.test_native_fmi3_description import FMI2, TIME_VR


def _fmi3() -> ET.Element:
    return ET.fromstring(fmi3_model_description(FMI2.encode(), TIME_VR))


def test_the_independent_time_is_a_continuous_float64_with_every_attribute_written():
    """FMI 3.0 §2.4.7: the independent variable ``time``, continuous, first among the
    variables.  Catches an attribute (variability, description, causality) dropped or changed,
    and time put after the model's variables."""
    variables = list(_fmi3().find("ModelVariables"))
    time = variables[0]
    assert time.tag == "Float64"
    assert time.attrib == {"name": "time", "valueReference": str(TIME_VR), "causality": "independent",
                           "variability": "continuous", "description": "Simulation time [s]"}
    assert list(time) == [] and [v.get("name") for v in variables].count("time") == 1


def test_each_variable_keeps_exactly_its_fmi2_attributes_and_start():
    """Every FMI 2.0 ScalarVariable attribute FMI 3.0 also has (name, valueReference,
    description, causality, variability, initial) is copied unchanged, no other attribute is
    added, a non-Float variable without variability (FMI 2.0's default continuous) or with
    continuous becomes discrete, and the start sits where FMI 3.0 wants it.  Catches
    ``initial`` (fmpy does not compare it above) or a description dropped, and a start moved."""
    old = ET.fromstring(FMI2.encode()).find("ModelVariables")
    new = [v for v in _fmi3().find("ModelVariables") if v.get("name") != "time"]
    assert len(new) == len(old)
    kept = ("name", "valueReference", "description", "causality", "variability", "initial")
    for scalar, element in zip(old, new):
        typed = scalar[0]
        expected = {k: v for k, v in scalar.attrib.items() if k in kept}
        tag = {"Real": "Float64", "Integer": "Int32"}.get(typed.tag, typed.tag)
        if tag != "Float64" and expected.get("variability", "continuous") == "continuous":
            expected["variability"] = "discrete"
        start = typed.get("start")
        if start is not None and tag != "String":
            expected["start"] = start
        assert (element.tag, element.attrib) == (tag, expected), scalar.get("name")
        if tag == "String" and start is not None:
            assert [(c.tag, c.attrib) for c in element] == [("Start", {"value": start})]
        else:
            assert list(element) == []
    # The description's own cases, spelled out: y's initial kept, flag discrete, label's start a child.
    by_name = {v.get("name"): v for v in new}
    assert by_name["y"].get("initial") == "calculated" and by_name["n"].get("initial") == "calculated"
    assert by_name["flag"].get("variability") == "discrete" and by_name["count"].get("variability") == "discrete"
    assert by_name["u"].get("description") == "in" and by_name["label"].get("start") is None


def test_the_cosimulation_element_declares_exactly_the_kept_capabilities_and_no_event_mode():
    """FMI 3.0 spells FMUState with a capital S; Event Mode, early return and intermediate
    update are declared off.  Catches one of the three declared true or dropped, a capability
    kept under FMI 2.0's spelling, or an FMI 2.0-only attribute carried over."""
    root = _fmi3()
    (cosim,) = root.findall("CoSimulation")
    assert cosim.attrib == {"modelIdentifier": "Probe", "needsExecutionTool": "false",
                            "canHandleVariableCommunicationStepSize": "false",
                            "canGetAndSetFMUState": "true", "canSerializeFMUState": "true",
                            "canBeInstantiatedOnlyOncePerProcess": "false", "hasEventMode": "false",
                            "canReturnEarlyAfterIntermediateUpdate": "false",
                            "providesIntermediateUpdate": "false"}


def test_the_root_carries_the_model_attributes_and_the_guid_as_instantiation_token():
    """Catches a model attribute dropped, FMI 2.0's guid or numberOfEventIndicators (not FMI
    3.0 attributes) carried over, and the elements out of FMI 3.0's order."""
    root = _fmi3()
    assert root.attrib == {"fmiVersion": "3.0", "modelName": "Probe", "description": "a probe",
                           "author": "parcosim", "generationTool": "test",
                           "variableNamingConvention": "structured", "instantiationToken": "{1234-abcd}"}
    assert [child.tag for child in root] == ["CoSimulation", "LogCategories", "DefaultExperiment",
                                             "ModelVariables", "ModelStructure"]
    assert [c.attrib for c in root.find("LogCategories")] == [
        {"name": "logStatusError", "description": "fmi3Error and fmi3Fatal"}, {"name": "logAll", "description": ""}]
    assert root.find("DefaultExperiment").attrib == {"startTime": "0.0", "stopTime": "2.5", "stepSize": "0.002"}


def test_the_structure_gives_value_references_and_keeps_a_missing_dependency_list_missing():
    """FMI 2.0 indices 3, 5, 7 are y (7), flag (12), n (6); dependencies 1 2 are u (10) and
    count (3).  Catches 0-based indices, an absent dependencies attribute written as empty
    (which says "depends on nothing"), and an initial unknown lost."""
    structure = _fmi3().find("ModelStructure")
    assert [(e.tag, e.attrib) for e in structure] == [
        ("Output", {"valueReference": "7", "dependencies": "10 3"}),
        ("Output", {"valueReference": "12", "dependencies": ""}),
        ("Output", {"valueReference": "6"}),
        ("InitialUnknown", {"valueReference": "7", "dependencies": "3"}),
        ("InitialUnknown", {"valueReference": "12", "dependencies": ""}),
        ("InitialUnknown", {"valueReference": "6"})]
