"""The SSP package's connectors read back from its SystemStructure.ssd (issue 31, pattern 3; seed
3501's survivor [23], fmus/ssp.py:229 then, fmus/ssp/export.py now): an input both connected and
given a value is an input connector only, with its value in the parameter set; an input given a
value and not connected is a parameter connector; outputs are output connectors.  FMUs made of
a model description only (test_oracles_export.py's): nothing is built."""
from __future__ import annotations

import xml.etree.ElementTree as ET
import zipfile

from fmus.cosim.system import Component, Connection, System
from fmus.ssp.export import export_ssp, read_ssp_parameters
from tests.fmus.export.test_oracles_export import fake_fmu


def _connector_elements(path):
    """(component name, connector element) of every connector in the package's SSD."""
    with zipfile.ZipFile(path) as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    for element in root.iter():
        if element.tag.endswith("}Component"):
            for connector in element.iter():
                if connector.tag.endswith("}Connector"):
                    yield element.get("name"), connector


def _connectors(path):
    return {(name, c.get("name")): c.get("kind") for name, c in _connector_elements(path)}


def test_a_connected_input_given_a_value_stays_an_input_connector_and_keeps_its_value(tmp_path):
    """Catches the "connected" test made on a wrong name (``c.name + name`` without the dot:
    the connected input declared a parameter connector too, refused as both), or an
    unconnected input with a value left without its parameter connector."""
    fmus = {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}
    system = System((Component("first", "Alpha", {"u": 0.25, "gain": 1.5}), Component("second", "Beta", {"u": -2.0})),
                    (Connection("first.y", "second.u"),), ("second.y",), stop_time=0.5, step=2e-3)
    path = export_ssp(system, tmp_path / "sys.ssp", fmus=fmus)
    connectors = _connectors(path)
    assert connectors[("second", "u")] == "input"
    assert connectors[("first", "u")] == "parameter" and connectors[("first", "gain")] == "parameter"
    assert connectors[("first", "y")] == "output" and connectors[("second", "y")] == "output"
    assert read_ssp_parameters(path) == {"first.u": 0.25, "first.gain": 1.5, "second.u": -2.0}


def test_an_integer_parameter_outside_32_bits_is_refused_naming_it(tmp_path):
    """Seed 3501's survivor [51] (fmus/ssp.py:64, the upper bound 2**31 - 1 -> 2**31 passed):
    the int32 ends are bound exactly (test_oracles_export.py), one past either end is refused."""
    import pytest

    fmus = {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}
    for value in (2 ** 31, -2 ** 31 - 1):
        system = System((Component("first", "Alpha", {"count": value}), Component("second", "Beta")),
                        (Connection("first.y", "second.u"),), ("second.y",), stop_time=0.5, step=2e-3)
        with pytest.raises(ValueError, match=rf"parameter first.count = {value} does not fit a 32-bit FMI Integer"):
            export_ssp(system, tmp_path / "sys.ssp", fmus=fmus)


def test_every_connector_carries_the_fmi_type_of_its_variable(tmp_path):
    """A parameter of each FMI type, an input and an output: each connector's one child is
    the ``ssc`` element of its variable's type (Real, Integer, Boolean, String), read back
    from the SSD beside its kind.  Catches a connector typed by its kind or by another
    variable, a type left out, or two children."""
    from tests.fmus.export.test_oracles_export import TYPES

    fmus = {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}
    values = {"gain": 1.5, "count": 3, "flag": True, "label": "x"}
    system = System((Component("first", "Alpha", values), Component("second", "Beta")),
                    (Connection("first.y", "second.u"),), ("second.y",), stop_time=0.5, step=2e-3)
    path = export_ssp(system, tmp_path / "sys.ssp", fmus=fmus)
    typed = {(name, c.get("name")): (c.get("kind"), [child.tag.split("}")[1] for child in c])
             for name, c in _connector_elements(path)}
    expected = {("first", name): ("parameter", [TYPES[name]]) for name in values}
    expected.update({("first", "y"): ("output", ["Real"]), ("second", "u"): ("input", ["Real"]),
                     ("second", "y"): ("output", ["Real"])})
    assert typed == expected
    assert read_ssp_parameters(path) == {f"first.{name}": value for name, value in values.items()}
