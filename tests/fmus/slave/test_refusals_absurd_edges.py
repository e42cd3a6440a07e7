"""The ABSURD bound (fmus/slave/refusals.py, docs/extremes.md: |value| <= 1e6 in SI units) met
exactly and passed by one ulp, through every slave's FMI calls: each Real parameter of every
slave and each input the slaves bound by it (the wheeled pendulum's torques, the balance
controller's sensors; the derivator's angles are in test_refusals_derivator.py).  At +-ABSURD no
refusal says "absurd"; one ulp beyond, the refusal names the variable and its value by ``repr``
word for word.  Seed 4101's survivor [135] (parcosim_derivator.py:93, ``<=`` -> ``<`` at the
derivator's input bound) turned out equivalent (an input at the bound goes on to the
per-input check, which takes it); these catch the bound dropped from a slave's list of checked
parameters or inputs, or met on the wrong side, in every slave.
"""
from __future__ import annotations

import math

import pytest
from pythonfmu.variables import Real

from fmus.slave.refusals import ABSURD
from tests.fmus.slave.test_extremes import GOOD, H, SLAVES, slave_class, set_variables

OVER = math.nextafter(ABSURD, math.inf)
#: The 5R plants' start point: a point 1e6 m away is refused as outside the workspace first.
START_POINT = {("FiveBarPlant", "x0"), ("FiveBarPlant", "y0"), ("ActuatedFiveBarPlant", "x0"),
               ("ActuatedFiveBarPlant", "y0")}
#: Inputs bounded by ABSURD in the slaves' own step (docs/extremes.md).
BOUNDED_INPUTS = [("WheeledPendulum", name) for name in ("tau_l", "tau_r", "tau_d")] + \
                 [("BalanceController", name) for name in ("enc_l", "enc_r", "gyro")]


def _real_parameters():
    return [pytest.param(model, v.name, id=f"{model}.{v.name}")
            for model in SLAVES for v in slave_class(model)(instance_name="scan").vars.values()
            if isinstance(v, Real) and v.causality is not None and v.causality.name == "parameter"]


def _initialised(model: str, name: str, value: float) -> str:
    slave = slave_class(model)(instance_name=model)
    set_variables(slave, {**GOOD[model][0], name: value})
    return slave.error


@pytest.mark.parametrize("model, name", _real_parameters())
def test_every_real_parameter_is_not_absurd_at_the_bound_and_is_refused_one_ulp_beyond(model, name, monkeypatch,
                                                                                      tmp_path):
    """+-ABSURD is never refused as absurd (another rule may refuse it, in its own words);
    +OVER is refused as absurd word for word (the start point first as outside the workspace);
    -OVER is refused naming the parameter and its value: as absurd, or first as negative where
    only -1 (the preset's value) or a positive value is allowed."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))     # tables of odd grids: not in the user's cache
    for value in (ABSURD, -ABSURD):
        assert "absurd" not in _initialised(model, name, value)
    absurd = f"initialisation refused: parameter {name} = {{!r}} is absurd: |{name}| must be <= 1e+06 (SI units) " \
             "(t = 0 s)"
    for value in (OVER, -OVER):
        error = _initialised(model, name, value)
        if (model, name) in START_POINT:
            assert error.startswith("initialisation refused: start point ") and f"{name}={value!r}" in error, error
            assert "is outside the workspace" in error
        elif value > 0.0:
            assert error == absurd.format(value)
        else:
            assert error == absurd.format(value) or \
                error.startswith(f"initialisation refused: parameter {name} = {value!r} ") and \
                ("is negative (use -1 for the preset's value)" in error or " must be >= " in error), error


def _stepped(model: str, name: str, value: float):
    slave = slave_class(model)(instance_name=model)
    set_variables(slave, GOOD[model][0])
    set_variables(slave, {**GOOD[model][1], name: value}, initialise=False)
    return slave.do_step(0.0, H), slave.error


@pytest.mark.parametrize("model, name", BOUNDED_INPUTS, ids=[f"{m}.{n}" for m, n in BOUNDED_INPUTS])
def test_an_input_bounded_by_absurd_is_taken_at_it_and_refused_one_ulp_beyond_naming_it(model, name):
    """At +-ABSURD the step is not refused as absurd (a torque of 1e6 N m may well topple the
    robot: that refusal has its own words); one ulp beyond either way the step is refused
    naming the input, its value and the time, nothing else."""
    for value in (ABSURD, -ABSURD):
        assert "absurd" not in _stepped(model, name, value)[1]
    for value in (OVER, -OVER):
        assert _stepped(model, name, value) == \
            (False, f"input {name} = {value!r} at t = 0 s is absurd: |{name}| must be <= 1e+06")
