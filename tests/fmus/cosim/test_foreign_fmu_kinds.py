"""A foreign FMU the master cannot run as FMI 2.0 co-simulation is refused before it is unzipped
(fmus/cosim/backends.py ``_unzipped``), naming the component, the file and its FMI version:
here a valid FMI 2.0 model-exchange-only FMU (no CoSimulation element).  Training sample
4263's [0], the test's ``or`` made ``and`` (only an FMU of another version *and* without
co-simulation refused), survived every test: they all ran co-simulation FMUs."""
from __future__ import annotations

import re
import zipfile

import pytest

from fmus.cosim import backends

MODEL_EXCHANGE_ONLY = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="M" guid="{g}">
  <ModelExchange modelIdentifier="M"/>
  <ModelVariables>
    <ScalarVariable name="x" valueReference="0" causality="output" variability="continuous" initial="exact">
      <Real start="0"/></ScalarVariable>
  </ModelVariables>
  <ModelStructure><Outputs><Unknown index="1"/></Outputs></ModelStructure>
</fmiModelDescription>"""


def test_a_model_exchange_only_fmu_is_refused_naming_the_component_file_and_version(tmp_path):
    fmu = tmp_path / "me_only.fmu"
    with zipfile.ZipFile(fmu, "w") as z:
        z.writestr("modelDescription.xml", MODEL_EXCHANGE_ONLY)
    with pytest.raises(ValueError, match=rf"^component drive1: {re.escape(str(fmu))} is not an FMI 2.0 "
                                         r"co-simulation FMU \(fmiVersion 2.0\)$"):
        backends._unzipped(fmu, "drive1")
    assert not any(key[0] == str(fmu) for key in backends._UNZIPPED)      # nothing unzipped, nothing kept
