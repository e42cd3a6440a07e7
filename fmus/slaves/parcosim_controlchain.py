"""FMI slave ``ControlChain``: a scene's components but its plant, one sample ahead.

For a package run by a Jacobi master (:mod:`scenarios.packaging.chain`): inputs are the plant's
measured outputs at the step's start (``q1_enc``, ``q2_enc`` on the bench); after
``doStep(t, h)`` the command outputs (``v_ref1``, ``v_ref2`` or ``tau1``, ``tau2``) are what
the plant is to apply over its next step [t + h, t + 2h], the sample of t + h computed
with the plant predicted by the chain's model of it (:class:`fmus.systemfmu.cores.ChainCore`);
after initialisation, what it applies over [0, h].  The recorded signals of the scene's
other components are outputs named by the signal (``traj.x_d``, ``ctrl.tau1``), at t + h
as the master records them.  The model of the plant is the system's component ``plant``,
with its parameters (``plant.x0`` ...): give it the real plant's.  ``corrections`` counts
the steps where the measurement moved the model.  The step size must be the scene's
communication step.  No direct feedthrough.

The module name is unique among parcosim slaves: all FMUs loaded in one process share
one Python interpreter and its module cache.
"""
from __future__ import annotations

from fmus.slave import designs
from fmus.systemfmu.cores import ChainCore, chain_interface
from fmus.systemfmu.slave_base import SystemSlave


class ControlChain(SystemSlave):
    """The sampled control chain of a parcosim scene, for a separate plant FMU."""

    #: 2 since the derivator's buffer holds its sections (layout 1: its dense step matrix).
    STATE_LAYOUT = 2

    takes_multiples = False
    description = ("The control chain of a parcosim scene (Coutinho 2019 5R robot) for a Jacobi master: "
                   "measurements in, the plant's commands one sample ahead out")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        designs.load(self.resources)   # what its build computed ahead (fmus/slave/designs.py)
        self.measured, commanded = chain_interface(self.system, self.plant)
        self.commanded = tuple(commanded)
        for name in self.measured:
            self.declare(name, "input", 0.0, f"The plant's output {name} at the step's start")
        for name in self.commanded:
            self.declare(name, "output", 0.0, f"The plant's input {name} over the next step")
        for signal in self.recorded_signals():
            self.declare(signal, "output", 0.0, f"Recorded signal {signal}")
        self.declare("corrections", "output", 0, "Steps where the measurement corrected the model of the plant")
        self.declare("zero_start", "parameter", True,
                     "The plant's first step [0, h] is commanded zero, in every master (false: the sample of t = 0, "
                     "as in parcosim's master, right only where the master passes the outputs after "
                     "initialisation to the first step)")

    def recorded_signals(self):
        return tuple(s for s in self.system.record if not s.startswith(f"{self.plant}."))

    def build(self, system):
        return ChainCore(system, self.plant, zero_start=bool(self.zero_start))

    def advance(self, current_time, step_size):
        self.core.step(current_time, step_size, {name: getattr(self, name) for name in self.measured})
        self.publish()

    def publish(self):
        core = self.core
        for name, value in core.command().items():
            setattr(self, name, value)
        recorded = core.recorded()
        for signal in self.recorded_signals():
            setattr(self, signal, recorded[signal])
        self.corrections = core.corrections
