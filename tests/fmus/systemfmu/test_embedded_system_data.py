"""The system as data inside a system FMU (fmus/systemfmu/cores.py): ``system_to_dict`` read
back through JSON by ``system_from_dict`` field for field (sub-steps, stop time, step, the record,
typed parameters), ``with_parameters`` taking each ``"instance.parameter"`` to its own instance
only, and ``component_parameters`` of an FMU-file component: each parameter's start value in
its type (a Boolean's ``"true"``/``"false"`` text included), the system's value over it
(issue 31: these ran only inside a built system FMU, where every component has sub-steps 1 and
its model's defaults).  Fast: FMUs made of a model description only."""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET
import zipfile

from fmus.cosim.system import Component, Connection, System
from fmus.systemfmu.cores import _fmu_parameters, component_parameters, system_from_dict, system_to_dict, \
    with_parameters

SYSTEM = System((Component("traj", "Trajectory", {"kind": "hold", "T": 0.25}, 1),
                 Component("traj2", "Trajectory", {"n": 3, "flag": True}, 3),
                 Component("deriv", "Derivator")),
                (Connection("traj.x_d", "deriv.u"), Connection("traj2.y_d", "deriv.v")),
                ("deriv.y", "traj.x_d"), stop_time=0.1 + 0.7, step=1e-3 / 3.0)


def test_the_system_goes_through_json_and_comes_back_equal_field_for_field():
    """Catches sub-steps, the stop time, the step or a connection's direction lost or swapped,
    and a parameter's type changed (an int read back as a float, a bool as an int)."""
    data = json.loads(json.dumps(system_to_dict(SYSTEM)))
    assert data == {"components": [{"name": "traj", "model": "Trajectory", "parameters": {"kind": "hold", "T": 0.25},
                                    "substeps": 1},
                                   {"name": "traj2", "model": "Trajectory", "parameters": {"n": 3, "flag": True},
                                    "substeps": 3},
                                   {"name": "deriv", "model": "Derivator", "parameters": {}, "substeps": 1}],
                    "connections": [["traj.x_d", "deriv.u"], ["traj2.y_d", "deriv.v"]],
                    "record": ["deriv.y", "traj.x_d"], "stop_time": 0.1 + 0.7, "step": 1e-3 / 3.0}
    back = system_from_dict(data)
    assert back == SYSTEM
    assert [type(v) for v in back.component("traj2").parameters.values()] == [int, bool]


def test_each_value_goes_to_its_own_instance_only_and_the_rest_is_kept():
    """``traj2.n`` is not ``traj``'s (a prefix without its dot would take it).  Catches the
    system's own values dropped where not given, sub-steps or the experiment lost."""
    changed = with_parameters(SYSTEM, {"traj.T": 0.5, "traj2.n": 9, "deriv.gain": 2.0, "nobody.x": 1})
    assert [c.parameters for c in changed.components] == [{"kind": "hold", "T": 0.5}, {"n": 9, "flag": True},
                                                          {"gain": 2.0}]
    assert [c.substeps for c in changed.components] == [1, 3, 1]
    assert (changed.connections, changed.record, changed.stop_time, changed.step) == \
        (SYSTEM.connections, SYSTEM.record, SYSTEM.stop_time, SYSTEM.step)


def _fmu(path):
    """An FMU whose parameters start at given texts (a Boolean's as "true", "1", "false"), one
    without a start, and an input."""
    root = ET.Element("fmiModelDescription", fmiVersion="2.0", modelName="M", guid="{0}")
    ET.SubElement(root, "CoSimulation", modelIdentifier="M")
    variables = ET.SubElement(root, "ModelVariables")
    rows = [("gain", "Real", "2.5"), ("count", "Integer", "-4"), ("on", "Boolean", "true"), ("one", "Boolean", "1"),
            ("off", "Boolean", "false"), ("label", "String", "a b"), ("unset", "Real", None)]
    for k, (name, type_, start) in enumerate(rows, start=1):
        sv = ET.SubElement(variables, "ScalarVariable", name=name, valueReference=str(k), causality="parameter",
                           variability="fixed" if start is not None else "tunable")
        ET.SubElement(sv, type_, **({"start": start} if start is not None else {}))
    sv = ET.SubElement(variables, "ScalarVariable", name="u", valueReference="9", causality="input")
    ET.SubElement(sv, "Real", start="7.0")
    ET.SubElement(root, "ModelStructure")
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("modelDescription.xml", ET.tostring(root, encoding="UTF-8", xml_declaration=True))
    return path


def test_an_fmu_files_parameters_are_its_start_values_in_their_types(tmp_path):
    """The start texts as fmpy reads them, a Boolean's made a bool (``bool("false")`` would be
    True; component_parameters converts the others).  Catches a Boolean's text taken as truthy,
    ``"1"`` not true, a parameter without a start or an input listed."""
    found = _fmu_parameters(_fmu(tmp_path / "m.fmu"))
    assert found == {"gain": ("Real", "2.5"), "count": ("Integer", "-4"), "on": ("Boolean", True),
                     "one": ("Boolean", True), "off": ("Boolean", False), "label": ("String", "a b")}
    assert found["off"][1] is False and found["on"][1] is True


def test_the_systems_values_override_the_starts_and_each_is_converted_to_its_type(tmp_path):
    fmu = _fmu(tmp_path / "m.fmu")
    system = System((Component("ext", str(fmu), {"gain": 1, "off": 1, "missing": 5}),), (), (), 0.01)
    values = component_parameters(system)
    assert values == {"ext.gain": 1.0, "ext.count": -4, "ext.on": True, "ext.one": True, "ext.off": True,
                      "ext.label": "a b"}
    assert [type(values[k]) for k in ("ext.gain", "ext.count", "ext.off")] == [float, int, bool]
    values = component_parameters(System((Component("ext", str(fmu)),), (), (), 0.01))
    assert (values["ext.gain"], values["ext.off"]) == (2.5, False)
