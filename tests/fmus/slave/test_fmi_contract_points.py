"""The slave base's rules held to their documented numbers (issue 31; seed 3601's survivors in
fmus/slave): the tolerance of a communication point (1e-9 of max(|t|, 1 ms), at most half the
last step: :meth:`fmus.slave.base.GuardedSlave._check_communication_point`), which outputs a
read in Initialization Mode calculates (not ``error`` nor ``refusal``), and the step-size
refusal's words in each mode of a drive (``accepted_steps``)."""
from __future__ import annotations

import pytest
from pythonfmu import Real, String

from fmus.slave.base import MAX_TIME, MIN_STEP
from fmus.slave.sampling import accepted_steps_text
from tests.fmus.slave.test_extremes import GOOD, make_slave, set_variables, slave_class


def _followed(model: str, steps, point_offset: float, start: float = 0.0) -> tuple:
    """A fresh ``model`` stepped by ``steps`` from ``start``, then asked to step from the next
    point plus ``point_offset``: (accepted, the expected point, the slave)."""
    slave = slave_class(model)(instance_name=model)
    slave.setup_experiment(start, None, None)
    slave.enter_initialization_mode()
    set_variables(slave, {**GOOD[model][0], **GOOD[model][1]}, initialise=False)
    slave.exit_initialization_mode()
    t = start
    for h in steps:
        assert slave.do_step(t, h), slave.error
        t += h
    return slave.do_step(t + point_offset, steps[-1]), t, slave


#: (model, start time, steps from it, the tolerance the rule gives at the next point): 1e-9 of
#: 1 ms below 1 ms, 1e-9 of |t| above it (before t = 0 too), half the last step when that is less.
TOLERANCES = [("Trajectory", 0.0, (1e-3,), 1e-12), ("Derivator", 0.0, (1e-3,), 1e-12),
              ("DCMotorDrive", 0.0, (1e-3,), 1e-12), ("Trajectory", 0.0, (4e-4,), 1e-12),
              ("Trajectory", 0.0, (0.5,), 5e-10), ("Trajectory", 0.0, (10.0, 1e-8), 5e-9),
              ("FiveBarPlant", -1000.0, (1e-3,), 1e-9 * (1000.0 - 1e-3))]


@pytest.mark.parametrize("model, start, steps, tolerance", TOLERANCES)
def test_a_communication_point_is_accepted_within_the_documented_tolerance_and_no_further(model, start, steps,
                                                                                           tolerance):
    """Points 0.8 and 1.25 times the rule's tolerance after the expected one, and before it:
    the first taken, the second refused naming both points.  Catches the floor of 1 ms taken
    as another time (seed 3601's [1]: 2 ms accepted 1.5e-12 s off at t = 1 ms), the relative
    factor changed, |t| dropped or taken as t (a plant started at t = -1000 s refused every
    rounded point), or the half-step cap lost (a 10 ns step at t = 10 s would take a point
    7 ns off)."""
    for sign in (1.0, -1.0):
        accepted, _, slave = _followed(model, steps, sign * 0.8 * tolerance, start)
        assert accepted, slave.error
        accepted, expected, slave = _followed(model, steps, sign * 1.25 * tolerance, start)
        assert not accepted
        assert f"does not follow the last one: the next doStep must start at t = {expected!r} s" in slave.error


def _in_initialization_mode(model: str):
    slave = slave_class(model)(instance_name=model)
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    built = []
    setup = slave.setup
    slave.setup = lambda: (built.append(True), setup())[1]
    return slave, built


@pytest.mark.parametrize("model", ["Derivator", "DCMotorDrive", "FiveBarPlant"])
def test_reading_error_or_refusal_in_initialization_mode_builds_nothing(model):
    """``error`` and ``refusal`` say why a step was refused; reading them before initialisation
    calculates nothing (a read of a Real output builds the model once, and initialisation keeps
    that build).  Catches the two String outputs counted among the calculated ones (seed
    3601's [37]: a read of ``error`` ran the model's setup)."""
    slave, built = _in_initialization_mode(model)
    strings = {v.name: v.value_reference for v in slave.vars.values() if isinstance(v, String)}
    assert slave.get_string([strings["error"], strings["refusal"]]) == ["", ""]
    assert built == []
    output = next(v for v in slave.vars.values()
                  if isinstance(v, Real) and v.causality is not None and v.causality.name == "output")
    slave.get_real([output.value_reference])
    assert built == [True]
    slave.exit_initialization_mode()
    assert built == [True] and slave.error == ""


def test_a_bad_parameter_read_through_error_in_initialization_mode_logs_nothing_until_initialisation():
    """A drive with R = 0 in Initialization Mode: reading ``error`` logs no warning (nothing
    is built), reading an output logs the one warning; initialisation then refuses naming R."""
    slave, built = _in_initialization_mode("DCMotorDrive")
    names = {v.name: v.value_reference for v in slave.vars.values()}
    slave.set_real([names["R"]], [0.0])
    slave.get_string([names["error"]])
    assert built == [] and slave.log_queue == []
    slave.get_real([names["tau"]])
    assert built == [True] and len(slave.log_queue) == 1
    assert "keep their start values" in slave.log_queue[0].msg
    slave.exit_initialization_mode()
    assert slave.error == "initialisation refused: parameter R must be > 0, got 0.0 (t = 0 s)"


BASE_RULE = f"any step size h with {MIN_STEP:g} s <= h and t + h <= {MAX_TIME:g} s"


@pytest.mark.parametrize("model", ["DCMotorDrive", "ActuatedFiveBarPlant"])
@pytest.mark.parametrize("mode", ["voltage", "current"])
def test_a_step_below_the_shortest_is_refused_with_the_rule_of_the_drives_mode(model, mode):
    """A step of 0.1 ns: the refusal names the step, the time, why, and the steps the model
    accepts in this mode, word for word (``step_size_message``): in voltage mode the base's
    rule marked "(voltage mode)", in current mode the sub-stepping rule.  Catches the mode's
    mark dropped (seed 3601's [131]) or the modes' rules swapped."""
    slave = make_slave(model, {"mode": mode})
    set_variables(slave, GOOD[model][1], initialise=False)
    assert not slave.do_step(0.0, 1e-10)
    accepts = f"{BASE_RULE} (voltage mode)" if mode == "voltage" else f"in current mode {accepted_steps_text()}"
    assert slave.error == (f"step size h = 1e-10 s at t = 0.0 s is below the shortest step {MIN_STEP:g} s; "
                           f"{model} accepts {accepts}")
    assert slave.accepted_steps() == accepts
