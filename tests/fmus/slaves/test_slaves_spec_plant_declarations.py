"""SpecPlant's declared starts (issue 31; session 43's training seed 4322 [3], [22] in
fmus/slaves/parcosim_specplant.py): SpecPlant is no registered slave (it needs a spec in its
resources), so the all-models checks of tests/fmus/slaves/test_slaves_input_starts.py do not
reach it.  Its inputs start at 0 (a world at rest, docs/master.md), its outputs at rest, its
start point is the spec's and its integrator parameters are :class:`plant.IntegratorSettings`'
defaults."""
from __future__ import annotations

from dataclasses import fields

from plant import IntegratorSettings
from plant.spec import load, spec_path
from tests.fmus.slave.test_parameter_extremes import SPEC, new_slave


def _by_causality(slave, causality: str) -> dict:
    return {v.name: getattr(slave, v.name) for v in slave.vars.values()
            if v.causality is not None and v.causality.name == causality}


def test_every_input_of_a_spec_plant_starts_at_zero_and_every_output_at_rest():
    """One torque input per actuated joint, each 0.0; every output 0.0 (``error`` and
    ``refusal`` empty).  Catches an input or output declared with another start."""
    slave = new_slave("SpecPlant")
    inputs = _by_causality(slave, "input")
    assert inputs and all(value == 0.0 and type(value) is float for value in inputs.values()), inputs
    rest = {float: 0.0, str: ""}
    outputs = _by_causality(slave, "output")
    assert outputs and all(value == rest[type(value)] and type(value) in rest for value in outputs.values()), outputs


def test_a_spec_plants_parameters_start_at_the_specs_point_and_the_integrators_defaults():
    """x0, y0, z0 are the spec's start point; method, substeps, rtol, atol and baumgarte are
    IntegratorSettings()'s, value and type.  Catches a start and a description swapped, or a
    default replaced."""
    slave = new_slave("SpecPlant")
    parameters = _by_causality(slave, "parameter")
    spec = load(spec_path(SPEC))
    assert [parameters[f"{axis}0"] for axis in "xyz"] == [float(v) for v in spec.start]
    defaults = IntegratorSettings()
    for name in ("method", "substeps", "rtol", "atol", "baumgarte"):
        expected = getattr(defaults, name)
        assert parameters[name] == expected and type(parameters[name]) is type(expected), name
    assert {f.name for f in fields(IntegratorSettings)} >= {"method", "substeps", "rtol", "atol", "baumgarte"}
