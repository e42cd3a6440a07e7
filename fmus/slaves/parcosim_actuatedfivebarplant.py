"""FMI slave ``ActuatedFiveBarPlant``: the 5R plant with both drives inside, one ODE.

A thin adapter over :class:`plant.actuated.ActuatedPlant`: ``FiveBarPlant`` and two
``DCMotorDrive`` in one FMU, their coupling removed.  The mechanism and the two armature
currents are integrated together (the plant's ``method``/``substeps``/``rtol`` apply to the
whole state); each drive's discrete current controller samples ``i_ref<j>`` and ``i_hat<j>``
at the step start and holds its voltage, as the separate drive does.  This is the
monolithic plant-motor coupling of the trade study (docs/trade.md): what a co-simulation
buys when the 0.6 ms electrical time constant and the mechanics are not split by the 1 ms
communication step.

Timing (one step from t to t + h): ``v<j>`` is the voltage applied over [t, t + h] (read it
into the observer, as the drive's ``v``), ``i<j>`` and ``tau<j>`` the current and shaft
torque at t + h; the mechanical outputs are those of ``FiveBarPlant``.  Parameters: the
plant's, the motors' with a suffix 1 (chain 1, default Table 16's motor) or 2 (Table 18's),
``mode`` and ``T`` of both current controllers.  No direct feedthrough.

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

from fmus.slave import budget
from fmus.slave import designs
from fmus.slave.base import MIN_STEP, GuardedSlave
from fmus.slave.sampling import declare_sample_phase
from fmus.slave.refusals import PRESET_VALUE, TINY, refuse_absurd
from fmus.slave.declarations import (CurrentLoopSteps, build_drive, build_plant, correct_plant, declare_drive_options,
                                     declare_motor, declare_plant, publish_plant)
from plant.actuated import ActuatedPlant

JOINTS = ("1", "2")


class ActuatedFiveBarPlant(CurrentLoopSteps, GuardedSlave):
    """The 5R mechanism and its two DC motor drives integrated as one system."""

    author = "parcosim"
    description = ("5R parallel robot with its two DC motor drives (Coutinho 2019, 5.66, 4.162, B.2, app. C) "
                   "as one ODE: current references in, motion out")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        designs.load(self.resources)   # what its build computed ahead (fmus/slave/designs.py)
        d = self.declare
        for j in JOINTS:
            d(f"i_ref{j}", "input", 0.0, f"Drive {j}: current reference, sampled at the step start (current mode) [A]")
            d(f"i_hat{j}", "input", 0.0, f"Drive {j}: observed (or measured) current at the step start "
                                         "(current mode) [A]")
            d(f"v_ref{j}", "input", 0.0, f"Drive {j}: commanded voltage, saturated at +-v_max (voltage mode) [V]")
        for j in JOINTS:
            d(f"tau{j}", "output", 0.0, f"Drive {j}: shaft torque kt i - friction (B.2 or LuGre) at the step end [N m]")
            d(f"v{j}", "output", 0.0, f"Drive {j}: voltage applied over the step just taken [V]")
            d(f"i{j}", "output", 0.0, f"Drive {j}: armature current at the step end [A]")
        declare_plant(self)
        for j in JOINTS:
            declare_motor(self, j, default_preset=f"motor{j}")
            declare_drive_options(self, j)
        d("mode", "parameter", "current",
          "Both drives: 'current' (controller K(z) on i_ref, i_hat) or 'voltage' (v_ref applied)")
        d("T", "parameter", 1e-3, "Current-controller sample time [s]; in current mode the step must divide it")
        declare_sample_phase(self)
        self.actuated = None
        self.idle_steps = 0    # a model in a controller: steps with the drives at 0 V (ChainCore)

    def setup(self):
        refuse_absurd(T=self.T)
        if 0.0 < self.T < MIN_STEP:
            raise ValueError(f"parameter T = {self.T!r} s must be >= {MIN_STEP:g} s")
        for j in JOINTS:
            value = getattr(self, f"L{j}")
            if value != PRESET_VALUE and 0.0 <= value < TINY:
                raise ValueError(f"parameter L{j} = {value!r} H must be > 0: the drives inside the plant integrate "
                                 "the armature current (use a separate DCMotorDrive with method 'quasi_static' "
                                 "for L = 0)")
        sim = build_plant(self)     # first: a bad plant parameter is refused before the drives' designs
        drives = [(int(j), build_drive(self, j, mode=self.mode, T=self.T, sample_phase=self.sample_phase))
                  for j in JOINTS]
        self.actuated = ActuatedPlant(sim, drives)
        self._publish()

    def current_loops(self):
        return [drive for _, drive in self.actuated.drives]

    def step(self, current_time, step_size):
        a = self.actuated
        a.plant.time = current_time
        if self.idle_steps:
            a.plant.check_step(step_size)
            self._advance(lambda limit: a.advance([0.0] * len(a.drives), step_size, limit), current_time, step_size)
            self.idle_steps -= 1
        else:
            self._advance(lambda limit: a.step((self.i_ref1, self.i_ref2), (self.i_hat1, self.i_hat2),
                                               (self.v_ref1, self.v_ref2), step_size, limit), current_time, step_size)
        self._publish()

    def _advance(self, run, current_time, step_size):
        """``run(max_evaluations)``, a step of the whole state, within the call's work limit (:mod:`fmus.slave.budget`)."""
        budget.step_plant(self.actuated.plant, run, current_time, step_size)

    def known_step_work(self) -> float:
        """The least CPU [s] a step is charged (:func:`fmus.slave.budget.known_step_work`)."""
        return budget.known_step_work(self.actuated.plant)

    def _publish(self):
        a = self.actuated
        publish_plant(self, a.plant)
        for j, (_, drive), tau in zip(JOINTS, a.drives, a.shaft_torques()):
            setattr(self, f"tau{j}", tau)
            setattr(self, f"v{j}", drive.v)
            setattr(self, f"i{j}", drive.i)

    # --- a model of the plant inside a controller (fmus.systemfmu.cores.ChainCore) -------------
    def snapshot(self):
        """The state before the next step (mechanism, currents, LuGre bristles), for :meth:`correct`."""
        a = self.actuated
        return a.plant.y, a.plant.time, a.currents, [d.z for _, d in a.drives]

    def correct(self, snapshot, measured: dict, step_size: float) -> bool:
        """Redo the last step (taken from ``snapshot``, with the voltages it held) from the
        state the ``measured`` outputs allow; the currents, unmeasured, restart from the
        snapshot's.  False, nothing changed, when the outputs agreed."""
        a = self.actuated
        y, time, currents, deflections = snapshot

        def redo():
            for (_, drive), i, z in zip(a.drives, currents, deflections):
                drive.i = i
                if drive.lugre is not None:
                    drive.z = z
            self._advance(lambda limit: a.advance([drive.v for _, drive in a.drives], step_size, limit), a.plant.time,
                          step_size)

        if not correct_plant(a.plant, (y, time), measured, redo, step_size):
            return False
        self._publish()
        return True
