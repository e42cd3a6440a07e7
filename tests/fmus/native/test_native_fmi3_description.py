"""fmus/native/fmi3xml.py on a description written here (every type, a String start, value
references that are not the indices, dependencies, log categories, a default experiment): fmpy
reads the FMI 2.0 input and the FMI 3.0 output (validated against FMI 3.0's schema and rules), and
they must say the same thing.  No FMU is built."""
from __future__ import annotations

import pytest
from fmpy import read_model_description

from fmus.native.fmi3xml import fmi3_model_description

FMI2 = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Probe" guid="{1234-abcd}" description="a probe"
    author="parcosim" generationTool="test" variableNamingConvention="structured" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="Probe" needsExecutionTool="false" canHandleVariableCommunicationStepSize="false"
      canGetAndSetFMUstate="true" canSerializeFMUstate="true" canBeInstantiatedOnlyOncePerProcess="false"/>
  <LogCategories>
    <Category name="logStatusError" description="fmi2Error and fmi2Fatal"/>
    <Category name="logAll"/>
  </LogCategories>
  <DefaultExperiment startTime="0.0" stopTime="2.5" stepSize="0.002"/>
  <ModelVariables>
    <ScalarVariable name="u" valueReference="10" causality="input" variability="continuous" description="in">
      <Real start="0.25"/></ScalarVariable>
    <ScalarVariable name="count" valueReference="3" causality="input" variability="discrete">
      <Integer start="-4"/></ScalarVariable>
    <ScalarVariable name="y" valueReference="7" causality="output" variability="continuous" initial="calculated">
      <Real/></ScalarVariable>
    <ScalarVariable name="label" valueReference="0" causality="parameter" variability="fixed">
      <String start="a &quot;b&quot;"/></ScalarVariable>
    <ScalarVariable name="flag" valueReference="12" causality="output" initial="calculated">
      <Boolean/></ScalarVariable>
    <ScalarVariable name="gain" valueReference="5" causality="parameter" variability="tunable">
      <Real start="1e-300"/></ScalarVariable>
    <ScalarVariable name="n" valueReference="6" causality="output" variability="discrete" initial="calculated">
      <Integer/></ScalarVariable>
  </ModelVariables>
  <ModelStructure>
    <Outputs>
      <Unknown index="3" dependencies="1 2"/>
      <Unknown index="5" dependencies=""/>
      <Unknown index="7"/>
    </Outputs>
    <InitialUnknowns>
      <Unknown index="3" dependencies="2"/>
      <Unknown index="5" dependencies=""/>
      <Unknown index="7"/>
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""
TIME_VR = 13
FLOAT = {"Real": "Float64", "Integer": "Int32"}


@pytest.fixture(scope="module")
def descriptions(tmp_path_factory):
    where = tmp_path_factory.mktemp("fmi3xml")
    (where / "fmi2.xml").write_text(FMI2)
    (where / "fmi3.xml").write_bytes(fmi3_model_description(FMI2.encode(), TIME_VR))
    return (read_model_description(str(where / "fmi2.xml"), validate=False),     # pythonfmu leaves a Boolean continuous
            read_model_description(str(where / "fmi3.xml"), validate=True))


def test_the_variables_are_the_fmi2_ones_in_fmi3_words(descriptions):
    """Catches a variable left out, put elsewhere than ModelVariables, given another reference,
    type, causality, variability or start (a String's, a tiny double's), and the independent
    ``time`` missing or at another reference."""
    md2, md3 = descriptions
    expected = [(v.name, v.valueReference, FLOAT.get(v.type, v.type), v.causality, v.start, v.description,
                 v.variability if v.type == "Real" or v.variability != "continuous" else "discrete")
                for v in md2.modelVariables]
    assert [(v.name, v.valueReference, v.type, v.causality, v.start, v.description, v.variability)
                         for v in md3.modelVariables if v.causality != "independent"] == expected
    (time,) = [v for v in md3.modelVariables if v.causality == "independent"]
    assert (time.name, time.valueReference, time.type) == ("time", TIME_VR, "Float64")
    assert next(v for v in md3.modelVariables if v.name == "flag").variability == "discrete"   # FMI 3.0's rule
    label = next(v for v in md3.modelVariables if v.name == "label")
    assert label.start == 'a "b"' and next(v for v in md3.modelVariables if v.name == "gain").start == "1e-300"


def test_the_structure_names_the_same_outputs_and_dependencies(descriptions):
    """Catches FMI 2.0's 1-based indices kept as FMI 3.0 value references, a dependency list
    dropped (depends on every input) or emptied, or an initial unknown lost."""
    md2, md3 = descriptions

    def named(unknowns):
        return [(u.variable.name, None if u.dependencies is None else [d.name for d in u.dependencies])
                for u in unknowns]

    assert named(md3.outputs) == named(md2.outputs) == [("y", ["u", "count"]), ("flag", []), ("n", None)]
    assert named(md3.initialUnknowns) == named(md2.initialUnknowns)


def test_the_model_attributes_experiment_and_log_categories_are_kept(descriptions):
    """Catches the GUID not the instantiation token, a model attribute or a CoSimulation
    capability dropped or inverted (FMI 3.0's capital S), the default experiment or a log
    category lost, or Event Mode declared."""
    md2, md3 = descriptions
    assert md3.fmiVersion == "3.0" and md3.guid == md2.guid == "{1234-abcd}"
    for name in ("modelName", "description", "author", "generationTool", "variableNamingConvention"):
        assert getattr(md3, name) == getattr(md2, name), name
    c2, c3 = md2.coSimulation, md3.coSimulation
    for name in ("modelIdentifier", "needsExecutionTool", "canHandleVariableCommunicationStepSize",
                 "canGetAndSetFMUstate", "canSerializeFMUstate", "canBeInstantiatedOnlyOncePerProcess"):
        assert getattr(c3, name) == getattr(c2, name), name
    assert c3.canHandleVariableCommunicationStepSize is False and c3.canGetAndSetFMUstate is True
    assert c3.hasEventMode is False and c3.providesIntermediateUpdate is False
    experiment = md3.defaultExperiment
    assert (experiment.startTime, experiment.stopTime, experiment.stepSize) == ("0.0", "2.5", "0.002")
    assert [(c.name, c.description) for c in md3.logCategories] == \
        [(c.name, (c.description or "").replace("fmi2", "fmi3")) for c in md2.logCategories]
    assert [c.name for c in md3.logCategories] == ["logStatusError", "logAll"]


def test_a_variable_named_time_or_at_times_reference_is_refused():
    """Catches a description whose variable would clash with the independent ``time`` accepted."""
    with pytest.raises(ValueError, match=r"the independent variable 'time' \(value reference 7\) clashes"):
        fmi3_model_description(FMI2.encode(), 7)
    with pytest.raises(ValueError, match=r"'time' \(value reference 99\) clashes"):
        fmi3_model_description(FMI2.replace('name="gain"', 'name="time"').encode(), 99)
