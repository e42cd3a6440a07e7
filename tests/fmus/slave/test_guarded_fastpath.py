"""The short cuts of :class:`fmus.slave.base.GuardedSlave`'s step path keep its refusals (issue 16).

``do_step`` checks a step size once and skips the check while the same h comes again;
``get_real``/``set_real`` resolve a list of value references once and cache it after
initialisation.  Each test takes a case where a cached answer would be wrong.
"""
from __future__ import annotations

import pytest
from pythonfmu import Real

from fmus.slave.base import MAX_TIME, FmiError
from tests.fmus.slave.test_extremes import make_slave, slave_class


def _vr(slave, name):
    return next(v.value_reference for v in slave.vars.values() if v.name == name)


def test_an_accepted_step_size_is_refused_when_the_step_ends_after_max_time():
    """Catches the fast path's cached acceptance of a step size letting a step through that ends after the
    largest time."""
    slave = slave_class("Trajectory")(instance_name="traj")
    start = MAX_TIME - 1.5e-3
    slave.setup_experiment(start, None, None)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    assert slave.do_step(start, 1e-3)
    # The same h again, but now t + h > MAX_TIME: the cached acceptance must not let it through.
    assert slave.do_step(start + 1e-3, 1e-3) is False
    assert "ends after" in slave.error


def test_another_step_size_is_checked_again():
    """Catches the fast path's cache accepting a new step size without the checks the first one had."""
    slave = make_slave("Derivator")            # h must divide its sample time T = 1 ms
    assert slave.do_step(0.0, 1e-3)
    assert slave.do_step(1e-3, 1e-3)
    assert slave.do_step(2e-3, 2e-3) is False
    assert "does not divide the sample time" in slave.error


def test_a_communication_point_off_the_last_step_is_refused():
    """Catches the fast path skipping the check that a step starts where the last one ended."""
    slave = make_slave("Derivator")
    assert slave.do_step(0.0, 1e-3)
    assert slave.do_step(1e-3 + 1e-6, 1e-3) is False
    assert "does not follow the last one" in slave.error


def test_a_parameter_set_before_initialisation_is_refused_after_it_with_the_same_list():
    """Catches the setter's cache, filled before initialisation, letting a parameter through after it, or
    applying part of a refused call."""
    slave = slave_class("DCMotorDrive")(instance_name="drive")
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    vrs = [_vr(slave, "omega0"), _vr(slave, "i_ref")]
    slave.set_real(vrs, [0.0, 0.5])
    slave.exit_initialization_mode()
    with pytest.raises(FmiError, match="parameter omega0 = 2.0 refused after initialisation"):
        slave.set_real(vrs, [2.0, 0.7])
    assert slave.omega0 == 0.0 and slave.i_ref == 0.5     # nothing was set
    slave.set_real(vrs[1:], [0.7])                         # the input alone: accepted, and cached
    slave.set_real(vrs[1:], [0.9])
    assert slave.i_ref == 0.9
    with pytest.raises(FmiError, match="tau is an output"):
        slave.set_real([_vr(slave, "tau")], [1.0])


def test_reads_of_many_lists_are_right_and_the_cache_stays_bounded():
    """Catches a value-reference cache that returns another list's values or grows without bound."""
    slave = make_slave("FiveBarPlant")
    reals = [v for v in slave.vars.values() if isinstance(v, Real)]
    assert len(reals) > 40
    for v in reals:                                   # more single lists than the cache holds
        assert slave.get_real([v.value_reference]) == [float(getattr(slave, v.name))]
    every = [v.value_reference for v in reals]
    assert slave.get_real(every) == [float(getattr(slave, v.name)) for v in reals]
    assert len(slave._GuardedSlave__readers) <= 32
    with pytest.raises(FmiError, match="value reference 99999 is no variable"):
        slave.get_real([every[0], 99999])


def test_the_shared_accessors_convert_each_variable_and_respect_setters():
    """attribute_reader/attribute_writer, the one implementation of GuardedSlave.get_real/set_real
    and InProcessInstance.bind: each value converted by its own type, a system FMU's flat
    "ctrl.lam" read as one attribute (not attrgetter's path), a property set through its setter."""
    from fmus.slave.base import attribute_reader, attribute_writer

    class Model:
        clamped = property(lambda self: self._clamped, lambda self, value: setattr(self, "_clamped", min(value, 1.0)))

    model = Model()
    setattr(model, "ctrl.lam", 40)
    model.count, model.on, model.text = 3.0, 1, "ok"
    read = attribute_reader(["ctrl.lam", "count", "on", "text"], [float, int, bool, str])
    assert [(type(v), v) for v in read(model)] == [(float, 40.0), (int, 3), (bool, True), (str, "ok")]
    assert [type(v) for v in attribute_reader(["count", "on"])(model)] == [float, float]
    assert attribute_reader(["text"], [str])(model) == ["ok"] and attribute_reader(["count"])(model) == [3.0]
    attribute_writer(Model, ["clamped"])(model, [0.5])
    assert model.clamped == 0.5
    attribute_writer(Model, ["count", "clamped"], [int, float])(model, [2.0, 5])
    assert (type(model.count), model.count, model.clamped) == (int, 2, 1.0)
    attribute_writer(Model, ["count", "on"], [float, float])(model, [7, True])
    assert [(type(v), v) for v in (model.count, model.on)] == [(float, 7.0), (float, 1.0)]


def test_an_in_process_instance_reads_outputs_of_every_type():
    """Catches an in-process instance that reads Integer, Boolean or String outputs as Real."""
    from fmus.cosim.backends import InProcessInstance

    instance = InProcessInstance("DCMotorDrive", "drive")
    instance.initialize({"T": -1e-3}, 0.0)                  # refused: the String output says why
    v = instance.variables
    instance.bind([v["i_ref"], v["omega"]], [v["tau"], v["error"]])
    instance.set_inputs([1, 2.5])
    assert (type(instance.slave.i_ref), instance.slave.omega) == (float, 2.5)
    tau, error = instance.get_outputs()
    assert type(tau) is float and isinstance(error, str) and error.startswith("initialisation refused: T must be > 0")
