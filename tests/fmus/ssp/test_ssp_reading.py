"""``read_ssp_parameters`` and ``read_ssp_experiment`` (fmus/ssp/export.py) on packages written
by hand as another tool would write them (SSP 1.0): bindings with a ``prefix``, inline
``ssd:ParameterValues``, every value type, Boolean ``1``/``0``; an experiment with only libcosim's
OSP step, with both steps (ours first, in either order), without a start time or without one at
all; refusals naming what is missing (issue 31: only packages written by export_ssp were read
back, which take none of these branches).  Nothing is run."""
from __future__ import annotations

import zipfile

import pytest

from fmus.ssp.export import NS, OSP_ANNOTATION, OSP_NS, STEP_ANNOTATION, read_ssp_experiment, read_ssp_parameters

HEAD = (f'<ssd:SystemStructureDescription xmlns:ssd="{NS["ssd"]}" xmlns:ssc="{NS["ssc"]}" '
        f'xmlns:ssv="{NS["ssv"]}" xmlns:osp="{OSP_NS}" xmlns:p="urn:parcosim:ssp" version="1.0" name="s">')


def _package(path, system="", experiment="", members=None):
    ssd = f'{HEAD}<ssd:System name="s"><ssd:Elements>{system}</ssd:Elements></ssd:System>{experiment}' \
          '</ssd:SystemStructureDescription>'
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("SystemStructure.ssd", ssd)
        for name, text in (members or {}).items():
            z.writestr(name, text)
    return path


def _ssv(parameters):
    return (f'<ssv:ParameterSet xmlns:ssv="{NS["ssv"]}" version="1.0" name="x"><ssv:Parameters>{parameters}'
            '</ssv:Parameters></ssv:ParameterSet>')


def test_bindings_from_files_and_inline_with_a_prefix_give_every_type(tmp_path):
    """Catches the prefix not stripped (or stripped from a name without it), inline values
    ignored, a Boolean ``1`` read as false or ``false`` as true, an Integer read as a float."""
    system = (
        '<ssd:Component name="a" source="resources/a.fmu"><ssd:ParameterBindings>'
        '<ssd:ParameterBinding source="resources/a.ssv" prefix="sub."/></ssd:ParameterBindings></ssd:Component>'
        '<ssd:Component name="b" source="resources/b.fmu"><ssd:ParameterBindings><ssd:ParameterBinding>'
        '<ssd:ParameterValues>' + _ssv('<ssv:Parameter name="on"><ssv:Boolean value="1"/></ssv:Parameter>'
                                       '<ssv:Parameter name="off"><ssv:Boolean value="false"/></ssv:Parameter>'
                                       '<ssv:Parameter name="text"><ssv:String value=" x "/></ssv:Parameter>') +
        '</ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings></ssd:Component>'
        '<ssd:Component name="c" source="resources/c.fmu"/>')
    a = _ssv('<ssv:Parameter name="sub.gain"><ssv:Real value="0.30000000000000004"/></ssv:Parameter>'
             '<ssv:Parameter name="count"><ssv:Integer value="-7"/></ssv:Parameter>')
    path = _package(tmp_path / "p.ssp", system, members={"resources/a.ssv": a})
    values = read_ssp_parameters(path)
    assert values == {"a.gain": 0.1 + 0.2, "a.count": -7, "b.on": True, "b.off": False, "b.text": " x "}
    assert type(values["a.count"]) is int and type(values["a.gain"]) is float


def test_a_parameter_without_a_value_or_a_missing_file_is_refused_naming_it(tmp_path):
    system = ('<ssd:Component name="a" source="resources/a.fmu"><ssd:ParameterBindings>'
              '<ssd:ParameterBinding source="resources/a.ssv"/></ssd:ParameterBindings></ssd:Component>')
    empty = _package(tmp_path / "e.ssp", system, members={
        "resources/a.ssv": _ssv('<ssv:Parameter name="gain"><ssv:Float64 value="1"/></ssv:Parameter>')})
    with pytest.raises(ValueError, match=r"^parameter 'gain': no Real, Integer, Boolean or String value$"):
        read_ssp_parameters(empty)
    missing = _package(tmp_path / "m.ssp", system)
    with pytest.raises(ValueError, match=r"m\.ssp: no resources/a\.ssv$"):
        read_ssp_parameters(missing)


def _experiment(*annotations, start='startTime="0.5" '):
    return f'<ssd:DefaultExperiment {start}stopTime="2.0"><ssd:Annotations>{"".join(annotations)}' \
           '</ssd:Annotations></ssd:DefaultExperiment>'


OURS = f'<ssc:Annotation type="{STEP_ANNOTATION}"><p:CommunicationStep value="0.002"/></ssc:Annotation>'
OSP = (f'<ssc:Annotation type="{OSP_ANNOTATION}"><osp:Algorithm><osp:FixedStepAlgorithm baseStepSize="0.0005"/>'
       '</osp:Algorithm></ssc:Annotation>')


@pytest.mark.parametrize("experiment, expected", [
    (_experiment(OSP), (0.5, 2.0, 5e-4)),                        # libcosim's step alone
    (_experiment(OURS, OSP), (0.5, 2.0, 2e-3)),                  # ours first ...
    (_experiment(OSP, OURS), (0.5, 2.0, 2e-3)),                  # ... whichever comes first
    (_experiment(start=""), (None, 2.0, None)),                  # no start, no step
    (_experiment(f'<ssc:Annotation type="{STEP_ANNOTATION}"/>', OSP), (0.5, 2.0, 5e-4)),   # ours empty
    ("", (None, None, None)),                                    # no experiment
])
def test_the_experiment_takes_our_step_before_libcosims_and_none_where_none_is_given(tmp_path, experiment, expected):
    """Catches libcosim's step taken over ours (or only when it comes first), a missing
    start read as 0, an empty annotation of ours taken for a step, and a package without an
    experiment refused."""
    assert read_ssp_experiment(_package(tmp_path / "p.ssp", experiment=experiment)) == expected


def test_a_package_without_its_structure_or_with_bad_xml_is_refused_naming_the_member(tmp_path):
    with zipfile.ZipFile(tmp_path / "none.ssp", "w") as z:
        z.writestr("other.txt", "x")
    with pytest.raises(ValueError, match=r"none\.ssp: no SystemStructure\.ssd$"):
        read_ssp_experiment(tmp_path / "none.ssp")
    with zipfile.ZipFile(tmp_path / "bad.ssp", "w") as z:
        z.writestr("SystemStructure.ssd", "<unclosed>")
    with pytest.raises(ValueError, match=r"bad\.ssp: SystemStructure\.ssd is not well-formed XML: "):
        read_ssp_parameters(tmp_path / "bad.ssp")
