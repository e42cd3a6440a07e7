"""The SpecPlant FMU of ``parcosim build-plant`` (fmus/export/specfmu.py) read in Initialization Mode
through fmpy: FMI 2.0 (4.2.4) has its outputs (initial="calculated") calculated from what was set so far,
not placeholders (session 39 left it open: x was to read 0.0 rather than the spec's start 0.02); and
what the built FMU declares and carries (its model options, the spec as checked)."""
from __future__ import annotations

import shutil

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from fmus.export.specfmu import build_plant_fmu
from plant.spec import load, spec_path

SPEC = "delta3"


@pytest.fixture(scope="module")
def spec_fmu(tmp_path_factory):
    return build_plant_fmu(SPEC, tmp_path_factory.mktemp("spec") / f"{SPEC}.fmu")


def _initialising(fmu, folder):
    md = read_model_description(str(fmu))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu), unzipdir=str(folder)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="spec")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    return slave, {v.name: v for v in md.modelVariables}


def _outputs(slave, variables) -> dict:
    outputs = [v for v in variables.values() if v.causality == "output" and v.type == "Real"]
    return dict(zip((v.name for v in outputs), slave.getReal([v.valueReference for v in outputs])))


@pytest.mark.parametrize("start", [None, (0.03, 0.0, -0.25)])
def test_outputs_read_in_initialization_mode_are_the_assembled_start_and_stay_after_exit(spec_fmu, tmp_path, start):
    """The platform reads the spec's start point (or the x0, y0, z0 set before the read), at rest, the loop
    closed; every output read there equals what the FMU publishes after fmi2ExitInitializationMode.
    Catches placeholders (0.0) read in Initialization Mode, a start point not taken from the parameters,
    or the outputs moved by the exit's build."""
    slave, variables = _initialising(spec_fmu, tmp_path / "unzipped")
    try:
        point = tuple(load(spec_path(SPEC)).start)
        if start is not None:
            slave.setReal([variables[f"{a}0"].valueReference for a in "xyz"], list(start))
            point = start
        during = _outputs(slave, variables)
        assert (during["x"], during["y"], during["z"]) == pytest.approx(point, abs=1e-12)
        assert (during["dx"], during["dy"], during["dz"]) == (0.0, 0.0, 0.0) and during["residual"] < 1e-9
        assert any(during[name] != 0.0 for name in during if name not in ("x", "y", "z", "residual")
                   and not name.startswith("d")), during          # the joints' angles are calculated too
        slave.exitInitializationMode()
        assert _outputs(slave, variables) == during
        slave.terminate()
        slave.freeInstance()
    finally:
        shutil.rmtree(tmp_path / "unzipped", ignore_errors=True)


def test_the_fmu_declares_variable_steps_and_states_and_carries_the_checked_spec(spec_fmu):
    """SpecPlant has no sample period, so it takes any step (as ``build_fmu`` gives the other plants:
    "true" without a sample period), and its state can be got, set and serialised (STATE_OPTIONS);
    the spec travels as ``plant_spec.toml``, the text ``load`` checked.  Catches a model option
    dropped from the build (fmpy's default "false" then written) and another text carried."""
    import zipfile

    from fmus.slave.designs import SPEC_RESOURCE

    cs = read_model_description(str(spec_fmu)).coSimulation
    assert (cs.canHandleVariableCommunicationStepSize, cs.canGetAndSetFMUstate, cs.canSerializeFMUstate) == \
        (True, True, True)
    with zipfile.ZipFile(spec_fmu) as z:
        assert z.read(f"resources/{SPEC_RESOURCE}").decode("utf-8") == load(spec_path(SPEC)).text
