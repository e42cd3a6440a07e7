"""The placeholders of a parcosim slave's outputs (initial="calculated", so no start in the
modelDescription): before the model calculates them every output holds the zero of its type,
and that is what a read in Initialization Mode gives when the model refuses its parameters
(docs/extremes.md: "the read keeps the start values and a warning", the plant's x = y = 0)."""
from __future__ import annotations

import pytest
from pythonfmu import Boolean, Integer, Real, String

from fmus.export.build import SLAVES
from tests.fmus.slave.test_extremes import GOOD, set_variables, slave_class

ZERO = {Real: 0.0, Integer: 0, Boolean: False, String: ""}


def _outputs(slave):
    """name -> (pythonfmu kind, variable) of every output but ``error`` and ``refusal``."""
    return {v.name: v for v in slave.vars.values()
            if v.causality is not None and v.causality.name == "output" and v.name not in ("error", "refusal")}


@pytest.mark.parametrize("model", sorted(SLAVES))
def test_every_output_is_the_zero_of_its_type_until_the_model_calculates_it(model):
    """A fresh instance, nothing set up: each output (read as the attribute the getters read)
    is exactly 0.0, 0, false or "" (a placeholder that looked like a value, say a torque of
    1 N m, would be taken for one by a master reading early; training seed 4213 [21])."""
    slave = slave_class(model)(instance_name=model)
    outputs = _outputs(slave)
    assert outputs
    for name, v in outputs.items():
        value = getattr(slave, name)
        assert type(value) is type(ZERO[type(v)]) and value == ZERO[type(v)], (name, value)


def test_a_drive_inside_the_plant_refused_in_initialization_mode_reads_zero_torques_currents_and_voltages():
    """The actuated plant with an inductance it refuses (L1 below the floor, "must be > 0"):
    a read of its outputs in Initialization Mode is not an error and gives the placeholders,
    zero for every drive's tau, v and i and for the plant's own outputs."""
    model = "ActuatedFiveBarPlant"
    slave = slave_class(model)(instance_name=model)
    logged = []
    slave.log = lambda message, status, category: logged.append(message)
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    set_variables(slave, {**GOOD[model][0], "L1": 1e-15}, initialise=False)
    reals = [v for v in _outputs(slave).values() if isinstance(v, Real)]
    assert {"tau1", "tau2", "v1", "v2", "i1", "i2"} <= {v.name for v in reals}
    assert slave.get_real([v.value_reference for v in reals]) == [0.0] * len(reals)
    assert len(logged) == 1 and "keep their start values: parameter L1 = 1e-15" in logged[0]
