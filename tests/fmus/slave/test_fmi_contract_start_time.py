"""The slave base's start time when a host never calls fmi2SetupExperiment (issue 31; seed
4001's out-of-sample survivor [288] in fmus/slave/base.py): FMI 2.0 makes t = 0 the default
start, and the base keeps it for the first communication point, the refusals' times and the
refusal record (:class:`fmus.slave.base.GuardedSlave`)."""
from __future__ import annotations

import json

import pytest

from tests.fmus.slave.test_extremes import GOOD, set_variables, slave_class


def _initialised_without_setup_experiment(model: str, parameters=None):
    """``model`` taken through Initialization Mode with no fmi2SetupExperiment before it."""
    slave = slave_class(model)(instance_name=model)
    slave.enter_initialization_mode()
    set_variables(slave, {**GOOD[model][0], **GOOD[model][1], **(parameters or {})}, initialise=False)
    slave.exit_initialization_mode()
    return slave


@pytest.mark.parametrize("model", ["Trajectory", "Derivator", "DCMotorDrive", "FiveBarPlant"])
def test_a_slave_never_told_its_start_time_takes_its_first_step_from_t_0(model):
    """Without fmi2SetupExperiment the first communication point is t = 0: a step from 0 is
    taken, the next from its end.  Catches the default start time taken as another number
    (seed 4001's [288]: 1.0 refused the step from 0 as off the expected point)."""
    slave = _initialised_without_setup_experiment(model)
    assert slave.do_step(0.0, 1e-3), slave.error
    assert slave.do_step(1e-3, 1e-3), slave.error


def test_an_initialisation_refused_without_setup_experiment_is_dated_t_0():
    """A drive with R = 0 and no fmi2SetupExperiment: the refusal and its record say t = 0."""
    slave = _initialised_without_setup_experiment("DCMotorDrive", {"R": 0.0})
    assert slave.error == "initialisation refused: parameter R must be > 0, got 0.0 (t = 0 s)"
    assert json.loads(slave.refusal)["time"] == 0.0
