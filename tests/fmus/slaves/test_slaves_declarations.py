"""Slaves that hold another slave's model declare its variables as that slave does: the
monolithic ``ActuatedFiveBarPlant`` (FiveBarPlant and two DCMotorDrive in one FMU) and the
separate ``DCMotorDrive`` and ``FiveBarPlant``, read from fresh slave objects (a variable's
attribute before initialisation is its declared start)."""
from __future__ import annotations

import pytest

from fmus.cosim.backends import InProcessInstance, slave_variables

JOINTS = ("1", "2")


def _fresh(model):
    slave = InProcessInstance(model, "x").slave
    return slave, slave_variables(slave)


@pytest.fixture(scope="module")
def slaves():
    return {model: _fresh(model) for model in ("ActuatedFiveBarPlant", "DCMotorDrive", "FiveBarPlant")}


def test_the_drives_inputs_start_as_the_separate_drives(slaves):
    """Catches an input of the drives inside the plant (``i_ref<j>``, ``i_hat<j>``, ``v_ref<j>``)
    missing, of another type or causality, or starting at another value than the separate
    DCMotorDrive's: a master that leaves it unset would feed the current loop another value."""
    actuated, a_vars = slaves["ActuatedFiveBarPlant"]
    drive, d_vars = slaves["DCMotorDrive"]
    inputs = [n for n, v in d_vars.items() if v.causality == "input" and n != "omega"]   # omega: the plant's own
    assert {"i_ref", "i_hat", "v_ref"} <= set(inputs)
    for name in inputs:
        for j in JOINTS:
            ours, theirs = a_vars[f"{name}{j}"], d_vars[name]
            assert (ours.type, ours.causality) == (theirs.type, theirs.causality), name
            start = getattr(actuated, f"{name}{j}")
            assert start == getattr(drive, name) and type(start) is type(getattr(drive, name)), f"{name}{j}"


def test_the_drives_outputs_and_the_plants_are_declared_as_the_separate_slaves(slaves):
    """Catches an output of the drives inside (``tau<j>``, ``v<j>``, ``i<j>``) or of the plant
    missing or declared with another causality, type or start than in the separate slaves."""
    actuated, a_vars = slaves["ActuatedFiveBarPlant"]
    drive, d_vars = slaves["DCMotorDrive"]
    plant, p_vars = slaves["FiveBarPlant"]
    for name in ("tau", "v", "i"):
        for j in JOINTS:
            assert (a_vars[f"{name}{j}"].type, a_vars[f"{name}{j}"].causality) == ("Real", "output")
            assert getattr(actuated, f"{name}{j}") == getattr(drive, name)
    plant_outputs = {n for n, v in p_vars.items() if v.causality == "output"}
    assert plant_outputs <= {n for n, v in a_vars.items() if v.causality == "output"}
    for name in plant_outputs:
        assert getattr(actuated, name) == getattr(plant, name) and a_vars[name].type == p_vars[name].type, name
    assert actuated.T == drive.T and actuated.mode == drive.mode
