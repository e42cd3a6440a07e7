"""The inputs' start values: docs/master.md says an unconnected input keeps its start value, and
every input of parcosim's own models starts at 0 (a component whose inputs nobody sets sees a
world at rest).  Held for every model's declarations and, through the master, for the current
observer, whose estimate (7.20) reads both its inputs: an input starting elsewhere would show up
as a current where nothing moves (issue 31: zero-by-default values held non-zero and at zero).
The outputs start at rest too: what a master reads in Initialization Mode from a refused setup."""
from __future__ import annotations

import importlib

import numpy as np
import pytest

from fmus.cosim.master import simulate
from fmus.cosim.system import Component, System
from fmus.slave.registry import SLAVES
from motor import get_motor_preset


@pytest.mark.parametrize("model", sorted(SLAVES))
def test_every_input_of_a_parcosim_model_starts_at_zero(model):
    """Catches an input declared with another start (an observer fed 1 rad/s, a plant 1 N m)."""
    slave = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)(instance_name="m")
    inputs = {v.name: getattr(slave, v.name) for v in slave.vars.values() if v.causality.name == "input"}
    assert all(value == 0.0 and type(value) is float for value in inputs.values()), inputs


def _estimates(**given) -> np.ndarray:
    """``obs.i_hat`` of a CurrentObserver alone, its inputs unconnected (``given``: a constant value)."""
    system = System((Component("obs", "CurrentObserver", dict(given)),), (), ("obs.i_hat",), stop_time=0.005)
    result = simulate(system)
    assert result.completed, result.error
    return result["obs.i_hat"]


@pytest.mark.parametrize("given", [{}, {"v": 3.0}, {"omega": 10.0}, {"v": 3.0, "omega": 10.0}])
def test_an_unconnected_input_of_the_observer_reads_its_start(given):
    """i_hat = (v - ke omega) / R (7.20, motor 1 of Table 16) with the inputs not given at 0:
    nothing given, no current; v alone, v / R; omega alone, -ke omega / R.  Catches ``v`` or
    ``omega`` starting at another value, or the given constant not reaching the input."""
    motor = get_motor_preset("motor1")
    v, omega = given.get("v", 0.0), given.get("omega", 0.0)
    estimates = _estimates(**given)
    assert estimates[0] == 0.0                    # i0 before the first step
    assert estimates[1:] == pytest.approx([(v - motor.ke * omega) / motor.R] * 5, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("model", sorted(SLAVES))
def test_every_output_of_a_parcosim_model_starts_at_rest(model):
    """The outputs' start values are what a master reads in Initialization Mode when the
    setup is refused (fmus/slave/base.py): a world at rest, every number 0 of its own type
    (0.0, 0, false) and every text empty.  Catches an output declared with another start
    (a drive reporting 1 V applied before any step)."""
    slave = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)(instance_name="m")
    outputs = {v.name: getattr(slave, v.name) for v in slave.vars.values() if v.causality.name == "output"}
    rest = {float: 0.0, int: 0, bool: False, str: ""}
    assert outputs and all(value == rest[type(value)] for value in outputs.values()), outputs


def test_a_drive_whose_setup_is_refused_reads_its_outputs_at_rest_in_initialization_mode():
    """Through the FMI calls: T below the least sample time refuses the setup, and a read of
    tau, v, i in Initialization Mode gets their start values, 0 each."""
    from fmus.slaves.parcosim_dcmotordrive import DCMotorDrive

    drive = DCMotorDrive(instance_name="drive")
    refs = {v.name: v.value_reference for v in drive.vars.values()}
    drive.setup_experiment(0.0, None, None)
    drive.enter_initialization_mode()
    drive.set_real([refs["T"]], [1e-9])
    assert list(drive.get_real([refs["tau"], refs["v"], refs["i"]])) == [0.0, 0.0, 0.0]
    assert "keep their start values" in drive._initial_warning
