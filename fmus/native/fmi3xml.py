"""The FMI 3.0 modelDescription.xml of a native FMU, from its FMI 2.0 one (docs/native.md, "FMI 3.0").

The variables, their value references, causalities, start values and descriptions, the
DefaultExperiment, the log categories and the ModelStructure's dependencies exist once, in the
FMI 2.0 description the pythonfmu slave declares (:func:`fmus.native.build.model_description`);
this module writes them in FMI 3.0's words: ``instantiationToken`` for ``guid``, one element
per variable named by its type (Real -> ``Float64``, Integer -> ``Int32``), a String's start
as a ``<Start value=...>`` child, the independent variable ``time`` FMI 3.0 requires,
``Output`` and ``InitialUnknown`` by value reference, and a co-simulation interface without
Event Mode, early return or intermediate update.
"""
from __future__ import annotations

from xml.etree import ElementTree as ET

#: FMI 2.0's type element -> FMI 3.0's variable element.
TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}
#: CoSimulation attributes kept (FMI 3.0 spells the state's capital S).
_KEPT = {"modelIdentifier": "modelIdentifier", "needsExecutionTool": "needsExecutionTool",
         "canBeInstantiatedOnlyOncePerProcess": "canBeInstantiatedOnlyOncePerProcess",
         "canGetAndSetFMUstate": "canGetAndSetFMUState", "canSerializeFMUstate": "canSerializeFMUState",
         "canHandleVariableCommunicationStepSize": "canHandleVariableCommunicationStepSize"}


def _variable(scalar: ET.Element) -> ET.Element:
    """One FMI 3.0 variable element from an FMI 2.0 ScalarVariable."""
    typed = scalar[0]
    kind = TYPES[typed.tag]
    attributes = {k: v for k, v in scalar.attrib.items() if k in ("name", "valueReference", "description",
                                                                   "causality", "variability", "initial")}
    if kind != "Float64" and attributes.get("variability", "continuous") == "continuous":
        attributes["variability"] = "discrete"   # FMI 3.0: only Float variables are continuous
    element = ET.Element(kind, attributes)
    start = typed.get("start")
    if start is not None:
        if kind == "String":
            ET.SubElement(element, "Start", value=start)
        else:
            element.set("start", start)
    return element


def _structure(structure: ET.Element, vrs: list[str]) -> ET.Element:
    """FMI 3.0's ModelStructure: FMI 2.0's 1-based indices as value references."""
    out = ET.Element("ModelStructure")

    def by_vr(indices: str) -> str:
        return " ".join(vrs[int(k) - 1] for k in indices.split())

    for group, tag in (("Outputs", "Output"), ("InitialUnknowns", "InitialUnknown")):
        for unknown in structure.find(group) if structure.find(group) is not None else ():
            element = ET.SubElement(out, tag, valueReference=vrs[int(unknown.get("index")) - 1])
            if unknown.get("dependencies") is not None:
                element.set("dependencies", by_vr(unknown.get("dependencies")))
    return out


def fmi3_model_description(fmi2_xml: bytes, time_vr: int) -> bytes:
    """The FMI 3.0 modelDescription.xml with the content of ``fmi2_xml`` (an FMI 2.0 one) and
    the independent variable ``time`` at value reference ``time_vr`` (the FMI 3.0 layer's
    ``PCN_TIME_VR``)."""
    old = ET.fromstring(fmi2_xml)
    root = ET.Element("fmiModelDescription", {"fmiVersion": "3.0"})
    for key in ("modelName", "description", "author", "generationTool", "generationDateAndTime",
                "variableNamingConvention"):
        if old.get(key) is not None:
            root.set(key, old.get(key))
    root.set("instantiationToken", old.get("guid"))
    cosim = old.find("CoSimulation")
    attributes = {new: cosim.get(key) for key, new in _KEPT.items() if cosim.get(key) is not None}
    ET.SubElement(root, "CoSimulation", {**attributes, "hasEventMode": "false",
                                         "canReturnEarlyAfterIntermediateUpdate": "false",
                                         "providesIntermediateUpdate": "false"})
    categories = old.find("LogCategories")
    if categories is not None:
        new = ET.SubElement(root, "LogCategories")
        for category in categories:
            description = (category.get("description") or "").replace("fmi2", "fmi3")
            ET.SubElement(new, "Category", name=category.get("name"), description=description)
    if old.find("DefaultExperiment") is not None:
        root.append(old.find("DefaultExperiment"))
    scalars = old.find("ModelVariables").findall("ScalarVariable")
    variables = ET.SubElement(root, "ModelVariables")
    if any(s.get("name") == "time" or s.get("valueReference") == str(time_vr) for s in scalars):
        raise ValueError(f"the independent variable 'time' (value reference {time_vr}) clashes with a variable")
    ET.SubElement(variables, "Float64", name="time", valueReference=str(time_vr), causality="independent",
                  variability="continuous", description="Simulation time [s]")
    for scalar in scalars:
        variables.append(_variable(scalar))
    root.append(_structure(old.find("ModelStructure"), [s.get("valueReference") for s in scalars]))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
