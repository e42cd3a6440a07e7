"""FMI slave ``FiveBarPlant``: a thin adapter over :class:`plant.PlantSimulator`.

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

from fmus.slave import budget
from fmus.slave.base import GuardedSlave
from fmus.slave.declarations import PLANT_OUTPUTS, build_plant, correct_plant, declare_plant, publish_plant

OUTPUTS = tuple(name for name, _ in PLANT_OUTPUTS)


class FiveBarPlant(GuardedSlave):
    """The 5R mechanism of thesis ch. 7.1 (forward dynamics 5.66), torque in, motion out."""

    author = "parcosim"
    description = "5R parallel robot (Coutinho 2019, ch. 4-5, 7.1): joint torques in, motion out"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.declare("tau1", "input", 0.0, "Torque on chain 1's base joint, CCW positive [N m]")
        self.declare("tau2", "input", 0.0, "Torque on chain 2's base joint, CCW positive [N m]")
        declare_plant(self)
        self.sim = None
        self.idle_steps = 0    # a model in a controller: steps with zero torques (ChainCore)

    def known_step_work(self) -> float:
        """The least CPU [s] a step is charged (:func:`fmus.slave.budget.known_step_work`)."""
        return budget.known_step_work(self.sim)

    def setup(self):
        self.sim = build_plant(self)
        publish_plant(self, self.sim)

    def step(self, current_time, step_size):
        sim = self.sim
        sim.time = current_time
        tau1, tau2 = (0.0, 0.0) if self.idle_steps else (self.tau1, self.tau2)
        if sim.settings.method == "rk4" and budget.active() is None:
            sim.step(tau1, tau2, step_size)     # the usual case: its count fits a call (checked at initialisation)
        else:
            self._advance(tau1, tau2, current_time, step_size)
        if self.idle_steps:
            self.idle_steps -= 1
        publish_plant(self, sim)

    def _advance(self, tau1, tau2, current_time, step_size):
        """The plant's step with the torques held, within the call's work limit (:mod:`fmus.slave.budget`)."""
        sim = self.sim
        budget.step_plant(sim, lambda limit: sim.step(tau1, tau2, step_size, limit), current_time, step_size)

    # --- a model of the plant inside a controller (fmus.systemfmu.cores.ChainCore) -------------
    def snapshot(self):
        """The state before the next step, for :meth:`correct`."""
        return self.sim.y, self.sim.time

    def correct(self, snapshot, measured: dict, step_size: float) -> bool:
        """Redo the last step (taken from ``snapshot``, with the same torques) from the state
        the ``measured`` outputs allow; False, nothing changed, when they agreed."""
        sim = self.sim
        if not correct_plant(sim, snapshot, measured, lambda: self._advance(self.tau1, self.tau2, sim.time, step_size),
                             step_size):
            return False
        publish_plant(self, sim)
        return True
