"""The FMI slave base of an FMU that contains a system (:mod:`fmus.systemfmu.cores`).

The system travels in the FMU's resources (``system.json``, written by
:mod:`fmus.systemfmu.export`); the slave declares from it, at instantiation:

* a parameter ``<instance>.<parameter>`` for every parameter of every inner component,
  typed and started as the inner component's (the system's value where it sets one);
  set one before initialisation and the inner component gets it;
* an output per recorded signal, named by the signal (``traj.x_d``), held as the master
  records it (row k at t = k h).

Subclasses add their own inputs and outputs and build their core in :meth:`build`.  The
FMU state is the slave's attributes and the inner system's state (every inner slave's,
the stepper's values and time): after ``fmi2SetFMUstate`` the FMU's time is the state's.
"""
from __future__ import annotations

import math

from pythonfmu import DefaultExperiment

from fmus.slave import budget
from fmus.systemfmu.cores import component_parameters, read_system, with_parameters
from fmus.slave.base import GuardedSlave


class SystemSlave(GuardedSlave):
    """Base of ``ClosedLoop`` and ``ControlChain``."""

    author = "parcosim"
    #: A doStep may take any whole number of the system's communication steps (else exactly one).
    takes_multiples = True

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.system, self.role, self.plant = read_system(self.resources)
        self.default_experiment = DefaultExperiment(0.0, self.system.stop_time, self.system.step)
        self._parameters = component_parameters(self.system)
        for name, value in self._parameters.items():
            self.declare(name, "parameter", value, f"Parameter {name.split('.', 1)[1]} of the inner "
                                                   f"component {name.split('.', 1)[0]}")
        self.core = None

    def recorded_signals(self) -> tuple:
        """The recorded signals this FMU publishes (subclasses may leave some out)."""
        return self.system.record

    def configured_system(self):
        """The system with the parameters as they are set now."""
        return with_parameters(self.system, {name: getattr(self, name) for name in self._parameters})

    def setup(self):
        self.core = self.build(self.configured_system())
        self.core.initialize()
        self.publish()

    def accepted_steps(self):
        """Its system's communication step (a whole multiple of it with ``takes_multiples``):
        its sampled components sample at the system's own steps, not at sub-steps of them."""
        h = self.system.step
        return f"a whole multiple of its system's step h = {h!r} s" if self.takes_multiples else f"its system's step h = {h!r} s"

    def check_step_size(self, current_time, step_size):
        """The base's rule, then the work limit (:mod:`fmus.slave.budget`): the step's communication
        steps times its components' inner steps must fit one call, refused before any is taken."""
        super().check_step_size(current_time, step_size)
        h = self.system.step
        steps = round(step_size / h)
        if steps < 1 or (steps > 1 and not self.takes_multiples) or self.core is None:
            return          # a step size the core refuses, naming what it accepts
        count, seconds = self.core.work_per_step()
        if count == 0:
            return
        most = max(1, math.floor(budget.CALL_CPU_SECONDS / seconds))
        with budget.call_budget() as left:
            left.require(steps * count, seconds / count, f"inner steps of {type(self).__name__}'s system",
                         f"step size h = {step_size!r} s at t = {current_time!r} s",
                         f"{steps:.6g} of its steps h = {h!r} s, {count} component steps each; take steps of at "
                         f"most {most * h:.6g} s ({most} of its steps)")

    def step(self, current_time, step_size):
        """The subclass's :meth:`advance` within the call's budget, its components' own
        cost (:data:`fmus.slave.budget.INNER_STEP` a doStep) spent first: they spend their
        integrators' evaluations from what is left."""
        with budget.call_budget() as left:
            left.spend(round(step_size / self.system.step) * self.core.inner_steps() * budget.INNER_STEP)
            self.advance(current_time, step_size)

    def advance(self, current_time, step_size):
        """Step the inner system from ``current_time`` over ``step_size`` and publish."""
        raise NotImplementedError

    def model_state(self) -> dict:
        """The slave's own attributes with ``core`` replaced by the inner system's state."""
        state = super().model_state()
        state["core"] = None if self.core is None else self.core.state()
        return state

    def restore_model_state(self, state: dict) -> None:
        """Restore the slave's attributes, then its inner system (built first in a fresh
        instance, from the restored parameters)."""
        state = dict(state)
        core = state.pop("core")
        super().restore_model_state(state)
        if core is None:
            self.core = None
            return
        if self.core is None:
            self.core = self.build(self.configured_system())
        self.core.restore(core)

    def build(self, system):
        raise NotImplementedError

    def publish(self):
        raise NotImplementedError
