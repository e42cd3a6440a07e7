"""FMI slave ``ClosedLoop``: a whole parcosim scene, its loop stepped inside the FMU.

``doStep(t, h)`` takes one communication step of the scene's system exactly as
``fmus.cosim.master.simulate`` does (in process, Gauss-Seidel, the master's order), so the FMU's
outputs are the rows of ``parcosim run SCENE``: ``x``, ``y`` (the end effector) and every
recorded signal under its name (``traj.x_d``, ``ctrl.tau1`` ...).  Every parameter of every
inner component is a parameter ``<instance>.<name>`` (``ctrl.lam``, ``plant.x0``).  The
step size must be the scene's communication step (1 ms).  No inputs.

Made per scene by ``parcosim export-fmu SCENE OUT.fmu`` (:func:`fmus.systemfmu.export.export_fmu`).
The module name is unique among parcosim slaves: all FMUs loaded in one process share
one Python interpreter and its module cache.
"""
from __future__ import annotations

from fmus.slave import designs
from fmus.systemfmu.cores import LoopCore
from fmus.systemfmu.slave_base import SystemSlave


class ClosedLoop(SystemSlave):
    """A parcosim scene's whole closed loop as one co-simulation FMU."""

    #: 2 since the derivator's buffer holds its sections (layout 1: its dense step matrix).
    STATE_LAYOUT = 2

    description = "A parcosim scene (Coutinho 2019 5R robot): the whole closed loop stepped inside one FMU"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        designs.load(self.resources)   # what its build computed ahead (fmus/slave/designs.py)
        self.declare("x", "output", 0.0, f"End effector x ({self.plant}.x) [m]")
        self.declare("y", "output", 0.0, f"End effector y ({self.plant}.y) [m]")
        for signal in self.system.record:
            self.declare(signal, "output", 0.0, f"Recorded signal {signal}")

    def build(self, system):
        return LoopCore(system)

    def advance(self, current_time, step_size):
        self.core.step(current_time, step_size)
        self.publish()

    def publish(self):
        core = self.core
        self.x = core.value(f"{self.plant}.x")
        self.y = core.value(f"{self.plant}.y")
        for signal in self.system.record:
            setattr(self, signal, core.value(signal))
