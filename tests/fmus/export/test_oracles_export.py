"""Every exported or serialised value read back and compared exactly (issue 31, pattern 3):
the SSP package's parameter sets, default experiment and baked start values (FMUs made of
a model description only, so nothing is built), the result CSV and metrics JSON of a run,
and sweep.csv's rows.  The values carry 17 significant digits, the ends of the 32-bit
integer range, XML's special characters and non-ASCII text, so a format that rounds, a
lost digit or a wrong parser shows."""
from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from fmus.ssp.export import export_ssp, read_ssp_experiment, read_ssp_parameters
from fmus.cosim.system import Component, Connection, System
from scenarios.run import runner as scenario_run
from scenarios.batch import sweep

#: Values no short format keeps: 17 significant digits, a subnormal, the int32 ends.
AWKWARD = {"gain": 0.1 + 0.2, "tiny": 5e-324, "big": -1.7976931348623157e308, "third": 1.0 / 3.0,
           "count": -2 ** 31, "limit": 2 ** 31 - 1, "flag": True, "label": 'a<b & "c" \u00e9\u00df'}
TYPES = {"gain": "Real", "tiny": "Real", "big": "Real", "third": "Real", "count": "Integer", "limit": "Integer",
         "flag": "Boolean", "label": "String"}
START = {"Real": "0.0", "Integer": "0", "Boolean": "false", "String": ""}


def fake_fmu(path, model):
    """An FMU holding only its FMI 2.0 co-simulation model description: the parameters of
    :data:`TYPES`, an input u and an output y."""
    root = ET.Element("fmiModelDescription", fmiVersion="2.0", modelName=model, guid="{0}")
    ET.SubElement(root, "CoSimulation", modelIdentifier=model)
    variables = ET.SubElement(root, "ModelVariables")
    rows = [(name, type_, "parameter", "fixed") for name, type_ in TYPES.items()]
    rows += [("u", "Real", "input", "continuous"), ("y", "Real", "output", "continuous")]
    for k, (name, type_, causality, variability) in enumerate(rows, start=1):
        sv = ET.SubElement(variables, "ScalarVariable", name=name, valueReference=str(k), causality=causality,
                           variability=variability)
        attributes = {"start": START[type_]} if causality != "output" else {}
        ET.SubElement(sv, type_, **attributes)
    structure = ET.SubElement(root, "ModelStructure")
    outputs = ET.SubElement(structure, "Outputs")
    ET.SubElement(outputs, "Unknown", index=str(len(rows)))
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("modelDescription.xml", ET.tostring(root, encoding="UTF-8", xml_declaration=True))
    return path


def _system():
    second = {"gain": 2.0 / 3.0, "count": 7, "flag": False, "label": "\u00fc"}
    components = (Component("first", "Alpha", dict(AWKWARD)), Component("second", "Beta", second))
    return System(components, (Connection("first.y", "second.u"),), ("second.y",), stop_time=0.1 + 0.7,
                  step=1e-3 / 3.0)


@pytest.fixture
def fmus(tmp_path):
    return {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}


@pytest.mark.parametrize("bake", [False, True])
def test_ssp_parameters_and_experiment_read_back_exactly(tmp_path, fmus, bake):
    system = _system()
    path = export_ssp(system, tmp_path / "out" / "sys.ssp", fmus=fmus, bake=bake)
    expected = {f"{c.name}.{name}": value for c in system.components for name, value in c.parameters.items()}
    got = read_ssp_parameters(path)
    assert got == expected
    assert all(type(got[k]) is type(v) for k, v in expected.items())
    assert read_ssp_experiment(path) == (0.0, system.stop_time, system.step)


def test_baked_fmus_start_at_the_instances_values_exactly(tmp_path, fmus):
    """bake: resources/<instance>.fmu's model description starts every parameter at the
    instance's value (read back with its type) and start_values.json holds the same."""
    system = _system()
    path = export_ssp(system, tmp_path / "sys.ssp", fmus=fmus, bake=True)
    readers = {"Real": float, "Integer": int, "Boolean": lambda s: {"true": True, "false": False}[s], "String": str}
    with zipfile.ZipFile(path) as ssp:
        for c in system.components:
            copy = tmp_path / f"{c.name}.fmu"
            copy.write_bytes(ssp.read(f"resources/{c.name}.fmu"))
            with zipfile.ZipFile(copy) as z:
                root = ET.fromstring(z.read("modelDescription.xml"))
                starts = {}
                for sv in root.iter("ScalarVariable"):
                    typed = next(iter(sv))
                    if sv.get("name") in c.parameters:
                        starts[sv.get("name")] = readers[typed.tag](typed.get("start"))
                assert starts == c.parameters
                assert json.loads(z.read("resources/start_values.json")) == c.parameters


def test_result_csv_reads_back_every_double_exactly(tmp_path):
    """Catches result.csv written with fewer digits than a double needs (subnormals, extreme exponents not
    read back bit for bit)."""
    rng = np.random.default_rng(31)
    t = np.arange(50) * (1e-3 / 3.0)
    columns = {"t": t, "plant.x": rng.normal(0, 1, 50) * 10.0 ** rng.integers(-300, 300, 50),
               "plant.y": np.full(50, 5e-324)}
    path = scenario_run.write_csv(tmp_path / "result.csv", columns)
    header = path.read_text().splitlines()[0]
    assert header == "t,plant.x,plant.y"
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    assert all(np.array_equal(data[:, k], v) for k, v in enumerate(columns.values()))


def test_metrics_json_reads_back_exactly_with_non_finite_values_as_null(tmp_path):
    """Catches metrics.json written with NaN or Infinity (not JSON), rounded doubles, or non-ASCII text
    mangled."""
    metrics = {"e_ef_mm": 0.1 + 0.2, "t_settle_s": math.inf, "nested": {"a": [1.0 / 3.0, math.nan, 7]},
               "completed": True, "name": "bench \u00e9"}
    path = scenario_run.write_json(tmp_path / "metrics.json", metrics)
    assert json.loads(path.read_text(encoding="utf-8")) == {
        "e_ef_mm": 0.1 + 0.2, "t_settle_s": None, "nested": {"a": [1.0 / 3.0, None, 7]}, "completed": True,
        "name": "bench \u00e9"}


def test_sweep_rows_read_back_exactly(tmp_path):
    """sweep.csv: a row appended is read back as the same values (floats to the last bit,
    the booleans, an error text with a comma, a quote and a newline made one line)."""
    header = sweep.columns(["plant.m0", "ctrl.lam"])
    rows = [{"sample": 3, "plant.m0": 0.1 + 0.2, "ctrl.lam": 70.00000000000001, "e_ef_mm": 1.0 / 3.0,
             "tau_ef_Nm": -2.5e-310, "e_ss_mm": math.inf, "e_ss_1s_mm": 0.0, "t_settle_s": 1e300,
             "completed": True, "outcome": "completed", "error_instance": "", "error_time": -0.0,
             "error_variable": "", "error_value": -0.0, "error_unit": "", "error_code": None, "error_reason": "",
             "error": "", "wall_s": 12.345678901234567},
            {"sample": 4, "plant.m0": 1.5, "ctrl.lam": 2.0, "e_ef_mm": math.nan, "tau_ef_Nm": 1.0, "e_ss_mm": 2.0,
             "e_ss_1s_mm": 3.0, "t_settle_s": 4.0, "completed": False, "outcome": "refused",
             "error_instance": "plant", "error_time": 0.1 + 0.2, "error_variable": "chain 1, elbow", "error_value": -math.inf,
             "error_unit": "N m", "error_code": 7, "error_reason": "singular", "error": 'x = "1",\n2', "wall_s": 0.5}]
    path = tmp_path / "sweep.csv"
    appender = sweep._Appender(path, header)
    for row in rows:
        appender.append(row)
    appender.close()
    back = sweep.read_rows(path, header)
    assert len(back) == 2 and math.isnan(back[1]["e_ef_mm"])
    back[1]["e_ef_mm"] = rows[1]["e_ef_mm"] = 0.0
    rows[1]["error"] = 'x = "1", 2'
    assert back == rows
    assert [type(v) for v in back[0].values()] == [type(v) for v in rows[0].values()]
    assert [type(v) for v in back[1].values()] == [type(v) for v in rows[1].values()]
