"""Every refused get, set and out-of-order call of the slave base, word for word (issue 31;
session 43's generalisation of seed 4001's [288] in fmus/slave/base.py): each names the call,
the variable, its value reference or value, what it is, and the time or mode
(``_refuse_get``, ``_refuse_set``, ``_refuse_out_of_order``, ``_mode``, ``_now``; the contract
table of docs/extremes.md), and changes nothing."""
from __future__ import annotations

import pytest

from fmus.slave.refusals import FmiError
from tests.fmus.slave.test_extremes import GOOD, set_variables, slave_class

MODEL = "DCMotorDrive"


def _drive(start: float = 0.0, steps: int = 0):
    """A DCMotorDrive initialised at ``start`` and stepped ``steps`` times by 1 ms; its value
    references by name."""
    slave = slave_class(MODEL)(instance_name="drive")
    slave.setup_experiment(start, None, None)
    slave.enter_initialization_mode()
    set_variables(slave, GOOD[MODEL][1], initialise=False)
    slave.exit_initialization_mode()
    for k in range(steps):
        assert slave.do_step(start + k * 1e-3, 1e-3), slave.error
    return slave, {v.name: v.value_reference for v in slave.vars.values()}


def _refusal(call, *arguments) -> str:
    with pytest.raises(FmiError) as refused:
        call(*arguments)
    return str(refused.value)


def test_each_refused_set_names_the_call_the_variable_its_value_and_the_time_and_sets_nothing():
    """A set whose first value is a good input and whose second is refused: the message names
    the second's value reference or name, its own value (not the first's), why, and the
    communication point after two steps (t = 2 ms); the input keeps its value.  Catches the
    message of one case given another's words, the value or the time taken from the wrong
    place, or the type names of the calls swapped."""
    slave, vr = _drive(steps=2)
    now = f"at t = {2e-3!r} s"
    old = {name: getattr(slave, name) for name in ("i_ref", "R", "tau", "pwm_counts", "internal_observer", "preset")}
    set_real = slave.set_real
    assert _refusal(set_real, [vr["i_ref"], 99999], [2.0, 1.5]) == (
        f"fmi2SetReal: value reference 99999 (value 1.5) is no variable of {MODEL} ({now}); nothing was set")
    assert _refusal(set_real, [vr["i_ref"], vr["error"]], [2.0, 1.5]) == (
        f"fmi2SetReal: error (value reference {vr['error']}) is a String, value 1.5 refused ({now}); "
        "nothing was set")
    assert _refusal(set_real, [vr["i_ref"], vr["R"]], [2.0, 3.0]) == (
        f"fmi2SetReal: parameter R = 3.0 refused after initialisation ({now}): a fixed parameter keeps its "
        f"value {old['R']!r}; nothing was set")
    assert _refusal(set_real, [vr["i_ref"], vr["tau"]], [2.0, 4.0]) == (
        f"fmi2SetReal: tau is an output (output), value 4.0 refused ({now}): it keeps {old['tau']!r}; "
        "nothing was set")
    assert _refusal(slave.set_integer, [vr["pwm_counts"]], [3]) == (
        f"fmi2SetInteger: parameter pwm_counts = 3 refused after initialisation ({now}): a fixed parameter "
        f"keeps its value {old['pwm_counts']!r}; nothing was set")
    assert _refusal(slave.set_boolean, [vr["internal_observer"]], [True]) == (
        f"fmi2SetBoolean: parameter internal_observer = True refused after initialisation ({now}): a fixed "
        f"parameter keeps its value {old['internal_observer']!r}; nothing was set")
    assert _refusal(slave.set_string, [vr["preset"]], ["motor2"]) == (
        f"fmi2SetString: parameter preset = 'motor2' refused after initialisation ({now}): a fixed parameter "
        f"keeps its value {old['preset']!r}; nothing was set")
    assert _refusal(slave.set_integer, [vr["tau"]], [1]) == (
        f"fmi2SetInteger: tau (value reference {vr['tau']}) is a Real, value 1 refused ({now}); nothing was set")
    assert {name: getattr(slave, name) for name in old} == old


def test_each_refused_get_names_the_call_the_variable_its_type_and_the_time():
    """A get of an unknown value reference or of a variable of another type, after two steps
    from t = 0.25 s: the message names the call, the value reference, the variable's own type
    and the communication point."""
    slave, vr = _drive(start=0.25, steps=2)
    now = f"at t = {0.25 + 1e-3 + 1e-3!r} s"
    assert _refusal(slave.get_real, [vr["i_ref"], 99999]) == (
        f"fmi2GetReal: value reference 99999 is no variable of {MODEL} ({now})")
    assert _refusal(slave.get_real, [vr["i_ref"], vr["error"]]) == (
        f"fmi2GetReal: error (value reference {vr['error']}) is a String ({now})")
    assert _refusal(slave.get_integer, [vr["pwm_counts"], vr["tau"]]) == (
        f"fmi2GetInteger: tau (value reference {vr['tau']}) is a Real ({now})")
    assert _refusal(slave.get_boolean, [vr["pwm_counts"]]) == (
        f"fmi2GetBoolean: pwm_counts (value reference {vr['pwm_counts']}) is a Integer ({now})")
    assert _refusal(slave.get_string, [vr["internal_observer"]]) == (
        f"fmi2GetString: internal_observer (value reference {vr['internal_observer']}) is a Boolean ({now})")
    assert _refusal(slave.get_string, [99999]) == f"fmi2GetString: value reference 99999 is no variable of {MODEL} ({now})"


def test_a_refused_call_right_after_initialisation_is_dated_at_the_start_time():
    """In Step Mode before any step the time is fmi2SetupExperiment's start (0.25 s); before
    initialisation the refusal says so instead of a time."""
    slave, vr = _drive(start=0.25)
    assert _refusal(slave.set_real, [vr["tau"]], [4.0]).endswith(
        f"value 4.0 refused (at t = 0.25 s): it keeps {slave.tau!r}; nothing was set")
    fresh = slave_class(MODEL)(instance_name="drive")
    assert _refusal(fresh.set_real, [vr["tau"]], [4.0]) == (
        "fmi2SetReal: tau is an output (output), value 4.0 refused (before initialisation): it keeps 0.0; "
        "nothing was set")
    assert _refusal(fresh.get_real, [99999]) == (
        f"fmi2GetReal: value reference 99999 is no variable of {MODEL} (before initialisation)")


ONCE = "it is allowed only once, between fmi2Instantiate and fmi2EnterInitializationMode; nothing was changed"
EXIT = ("it ends Initialization Mode (after fmi2EnterInitializationMode); nothing was changed, the model is "
        "not rebuilt")


def test_each_call_out_of_order_names_the_call_its_argument_and_the_mode():
    """fmi2SetupExperiment and fmi2EnterInitializationMode after fmi2EnterInitializationMode,
    fmi2ExitInitializationMode outside Initialization Mode: the call, the start time given, and
    the mode (in Initialization Mode, in Step Mode with the time, after fmi2Terminate, before
    fmi2EnterInitializationMode), word for word; the start time stays the first one."""
    fresh = slave_class(MODEL)(instance_name="drive")
    assert _refusal(fresh.exit_initialization_mode) == (
        f"fmi2ExitInitializationMode refused before fmi2EnterInitializationMode: {EXIT}")
    fresh.setup_experiment(0.25, None, None)
    fresh.enter_initialization_mode()
    assert _refusal(fresh.setup_experiment, 0.5, None, None) == (
        f"fmi2SetupExperiment (start_time = 0.5) refused in Initialization Mode: {ONCE}")
    assert _refusal(fresh.enter_initialization_mode) == f"fmi2EnterInitializationMode refused in Initialization Mode: {ONCE}"
    set_variables(fresh, GOOD[MODEL][1], initialise=False)
    fresh.exit_initialization_mode()
    assert fresh.do_step(0.25, 1e-3), fresh.error     # the refused 0.5 s changed nothing

    slave, _ = _drive(start=0.25, steps=1)
    step_mode = f"in Step Mode (at t = {0.25 + 1e-3!r} s)"
    assert _refusal(slave.setup_experiment, 0.5, None, None) == (
        f"fmi2SetupExperiment (start_time = 0.5) refused {step_mode}: {ONCE}")
    assert _refusal(slave.enter_initialization_mode) == f"fmi2EnterInitializationMode refused {step_mode}: {ONCE}"
    assert _refusal(slave.exit_initialization_mode) == f"fmi2ExitInitializationMode refused {step_mode}: {EXIT}"
    slave.terminate()
    assert _refusal(slave.setup_experiment, 0.0, None, None) == (
        f"fmi2SetupExperiment (start_time = 0.0) refused after fmi2Terminate: {ONCE}")
    assert _refusal(slave.exit_initialization_mode) == f"fmi2ExitInitializationMode refused after fmi2Terminate: {EXIT}"
