"""What export_ssp refuses, word for word, and what it converts (fmus/ssp/export.py): each refusal
names the component, signal or value and leaves no file; a value of another Python type that is
exactly a value of the variable's FMI type is written as that type and read back so (issue 31:
error paths naming variable and value; every exported value read back).  The same refusals run
through built FMUs in the slow test_ssp.py; here the FMUs are model descriptions only: fast."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fmus.cosim.system import Component, Connection, System
from fmus.ssp.export import export_ssp, read_ssp_parameters
from tests.fmus.export.test_oracles_export import fake_fmu


@pytest.fixture
def fmus(tmp_path):
    return {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}


def _system(a=None, b=None, connections=(("a.y", "b.u"),), record=("b.y",), substeps=1):
    return System((Component("a", "Alpha", dict(a or {}), substeps), Component("b", "Beta", dict(b or {}))),
                  tuple(Connection(s, t) for s, t in connections), tuple(record), stop_time=0.1)


CASES = [
    (dict(substeps=2), {}, "component a: substeps = 2; SSP 1.0 has no per-component step, so multi-rate systems "
                           "cannot be exported (set substeps=1)"),
    (dict(record=("a.nothing",)), {}, "recorded signal a.nothing: Alpha has no variable 'nothing'"),
    (dict(record=("a.u",)), {}, "recorded signal a.u is a input; only outputs and connected inputs can be recorded "
                                "(fmpy's SSP runner needs every declared input connected)"),
    (dict(connections=(("b.u", "a.u"),)), {}, "connection b.u -> a.u: the source is a input, not an output"),
    (dict(connections=(("a.y", "b.y"),)), {}, "connection a.y -> b.y: the target is a output, not an input"),
    (dict(connections=(("a.y", "b.gain"),)), {}, "connection a.y -> b.gain: the target is a parameter, not an input"),
    (dict(a={"y": 1.0}), {}, "parameter a.y: Alpha's 'y' is a output, not a parameter or input"),
    (dict(a={"gain": "x"}), {}, "parameter a.gain = 'x' (str) is no Real value"),
    (dict(a={"gain": True}), {}, "parameter a.gain = True (bool) is no Real value"),
    (dict(b={"gain": math.inf}), {}, "parameter b.gain = inf is not finite"),
    (dict(a={"count": 1.5}), {}, "parameter a.count = 1.5 (float) is no Integer value"),
    (dict(a={"count": False}), {}, "parameter a.count = False (bool) is no Integer value"),
    (dict(a={"flag": 2}), {}, "parameter a.flag = 2 (int) is no Boolean value"),
    (dict(a={"flag": -1}), {}, "parameter a.flag = -1 (int) is no Boolean value"),
    (dict(a={"flag": 0.0}), {}, "parameter a.flag = 0.0 (float) is no Boolean value"),
    (dict(a={"flag": "true"}), {}, "parameter a.flag = 'true' (str) is no Boolean value"),
    (dict(a={"count": np.float64(2.5)}), {}, "parameter a.count = np.float64(2.5) (float64) is no Integer value"),
    (dict(b={"gain": math.nan}), {}, "parameter b.gain = nan is not finite"),
    (dict(b={"gain": -math.inf}), {}, "parameter b.gain = -inf is not finite"),
    (dict(a={"label": 3}), {}, "parameter a.label = 3 (int) is no String value"),
    (dict(a={"label": "a\x01b"}), {}, "parameter a.label = 'a\\x01b' holds control characters XML cannot carry"),
    (dict(a={"label": "\x1f"}), {}, "parameter a.label = '\\x1f' holds control characters XML cannot carry"),
    (dict(a={"label": "\x00"}), {}, "parameter a.label = '\\x00' holds control characters XML cannot carry"),
    ({}, dict(instance_fmus={"a": "Alpha"}, bake=False),
     "instance_fmus: an instance's own FMU goes into the package only with bake=True"),
    ({}, dict(instance_fmus={"zz": "Alpha", "a": "Alpha"}), "instance_fmus: no instance zz in the system"),
    ({}, dict(instance_fmus={"a": "Beta"}), "{Beta} holds model 'Beta', not 'Alpha'"),
]


@pytest.mark.parametrize("system, options, message", CASES)
def test_what_cannot_be_exported_is_refused_naming_it_and_no_file_is_left(fmus, tmp_path, system, options, message):
    """Catches each check dropped, inverted or naming another component, signal or value, and a
    partial package left behind."""
    options = {k: (v if k != "instance_fmus" else {i: fmus[m] for i, m in v.items()}) for k, v in options.items()}
    out = tmp_path / "out"
    with pytest.raises(ValueError) as refused:
        export_ssp(_system(**system), out / "sys.ssp", fmus=fmus, **options)
    assert str(refused.value) == message.format(Beta=fmus["Beta"])
    assert not out.exists() or list(out.iterdir()) == []


def test_a_path_a_model_name_and_an_fmu_that_cannot_be_read_are_named(fmus, tmp_path):
    with pytest.raises(ValueError, match=r"sys.zip: an SSP package must end in '.ssp'$"):
        export_ssp(_system(), tmp_path / "sys.zip", fmus=fmus)
    system = System((Component("a", "x/y"),), (), (), stop_time=0.1)
    with pytest.raises(ValueError, match=r"^model name 'x/y' cannot name a file resources/x/y.fmu$"):
        export_ssp(system, tmp_path / "sys.ssp")
    junk = tmp_path / "junk.fmu"
    junk.write_bytes(b"not a zip")
    with pytest.raises(ValueError, match=f"^cannot read the model description of {junk}: "):
        export_ssp(_system(), tmp_path / "sys.ssp", fmus={**fmus, "Alpha": junk})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["Alpha.fmu", "Beta.fmu", "junk.fmu"]


def test_values_of_another_python_type_are_written_as_the_variables_type(fmus, tmp_path):
    """3.0 for an Integer is 3, 1 for a Boolean is True, numpy's scalars are their Python values:
    read back with the variable's type.  Catches a value written as given (3.0 into an
    Integer's XML) or a conversion that changes it."""
    given = {"count": 3.0, "limit": np.int64(-7), "flag": 1, "gain": np.float32(0.5), "tiny": 2, "label": "é\tx"}
    path = export_ssp(_system(a=given, b={"flag": np.bool_(False)}), tmp_path / "sys.ssp", fmus=fmus)
    got = read_ssp_parameters(path)
    expected = {"a.count": 3, "a.limit": -7, "a.flag": True, "a.gain": 0.5, "a.tiny": 2.0, "a.label": "é\tx",
                "b.flag": False}
    assert got == expected
    assert {name: type(value) for name, value in got.items()} == {name: type(value) for name, value in expected.items()}


def test_the_edges_of_each_types_accepted_values_are_written_and_read_back_exactly(fmus, tmp_path):
    """Seed 4101's survivor [76] (fmus/ssp/export.py:277, the Boolean ints ``(0, 1)`` -> ``(1, 1)``
    passed: only 1 was ever given).  FMI's Boolean is 0 or 1 (fmi2Boolean is an int), so both
    ints, as Python or numpy scalars, are accepted and read back as False and True; the only
    control characters XML 1.0 carries (tab, newline, carriage return) and the first printable
    ones (space, and DEL, which XML allows) are kept; a float or numpy float that is an integer
    is an Integer.  The refusals just past these edges are in :data:`CASES`."""
    a = {"flag": 0, "label": " \t\n\r\x7f", "count": np.float64(-4.0), "limit": np.int32(-2 ** 31),
         "gain": -0.0}
    b = {"flag": np.int64(1), "label": "", "count": np.uint8(255), "gain": np.float64(5e-324)}
    path = export_ssp(_system(a=a, b=b), tmp_path / "sys.ssp", fmus=fmus)
    got = read_ssp_parameters(path)
    expected = {"a.flag": False, "a.label": " \t\n\r\x7f", "a.count": -4, "a.limit": -2 ** 31, "a.gain": -0.0,
                "b.flag": True, "b.label": "", "b.count": 255, "b.gain": 5e-324}
    assert got == expected
    assert {name: type(value) for name, value in got.items()} == {name: type(value) for name, value in expected.items()}
    assert math.copysign(1.0, got["a.gain"]) == -1.0   # the sign of zero survives the text
    a_flag = np.int64(0)
    path = export_ssp(_system(a={"flag": a_flag}), tmp_path / "sys2.ssp", fmus=fmus)
    assert read_ssp_parameters(path) == {"a.flag": False}
