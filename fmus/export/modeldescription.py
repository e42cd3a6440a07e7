"""Give pythonfmu's modelDescription.xml its ModelStructure.

pythonfmu 0.7 writes an empty ModelStructure (pythonfmu issues 193, 258):
``fmpy validate`` reports outputs missing from it, and importers must assume
every output depends directly on every input.  :func:`fix_model_structure`
lists each output under ``Outputs`` with its direct-feedthrough inputs and
under ``InitialUnknowns`` with the inputs and parameters it is computed from
at initialisation.
"""
from __future__ import annotations

import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

from fmus.export.archive import rewrite


def model_structure(root: ET.Element, feedthrough: dict) -> ET.Element:
    """A ModelStructure element for the variables of ``root``.

    Parameters
    ----------
    root : Element
        The ``fmiModelDescription`` element.
    feedthrough : dict
        Output name -> names of the inputs it depends on directly; outputs
        not listed have no direct feedthrough.
    """
    variables = root.find("ModelVariables").findall("ScalarVariable")
    index = {v.get("name"): k + 1 for k, v in enumerate(variables)}   # 1-based (FMI 2.0 §2.2.8)
    unknown_names = set(feedthrough) - set(index)
    if unknown_names:
        raise ValueError(f"feedthrough names unknown variables: {sorted(unknown_names)}")
    parameters = [index[v.get("name")] for v in variables if v.get("causality") == "parameter"]
    structure = ET.Element("ModelStructure")
    outputs = ET.SubElement(structure, "Outputs")
    initial = ET.SubElement(structure, "InitialUnknowns")
    for v in variables:
        if v.get("causality") != "output":
            continue
        inputs = sorted(index[name] for name in feedthrough.get(v.get("name"), ()))
        ET.SubElement(outputs, "Unknown", index=str(index[v.get("name")]),
                      dependencies=" ".join(map(str, inputs)))
        ET.SubElement(initial, "Unknown", index=str(index[v.get("name")]),
                      dependencies=" ".join(map(str, sorted(inputs + parameters))))
    return structure


def fix_model_structure(fmu: Path, feedthrough: dict) -> None:
    """Rewrite the FMU's modelDescription.xml in place with a full ModelStructure."""
    fmu = Path(fmu)
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    old = root.find("ModelStructure")
    position = list(root).index(old)
    root.remove(old)
    root.insert(position, model_structure(root, feedthrough))
    ET.indent(root)
    xml = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    rewrite(fmu, fmu, {"modelDescription.xml": xml})
