"""The compiled adapters of parcosim's models (:mod:`fmus.cosim.compiled`).

One class per model, registered by :func:`fmus.cosim.adapter.register`: which of the slave's
variables the kernel's I/O array ``x`` holds (inputs first), the model arrays the kernel
steps (taken from the initialised slave's model objects, so the compiled loop and the
Python path step the same state), the C I/O function (``kernel``) and its ``context``.  A new model
adds its class here (or in its own module imported by this one); the generator does not
change.
"""
from __future__ import annotations

import ctypes

import kernels
from controller import derivators, fastbalance, law, trajectories
from plant import wheeled_kernel
from plant.actuated import kernel_context as actuated_context
from plant.fast5r import TERMS_OF

from fmus.cosim.adapter import Adapter, NotCompilable, register
from fmus.slave.refusals import ABSURD
from fmus.slave.declarations import PLANT_OUTPUTS
from fmus.slave.sampling import HOLD_FIRST_PARAMETER, PHASE_PARAMETER, substeps_of

_PLANT_OUTPUTS = tuple(name for name, _ in PLANT_OUTPUTS)


def _samples_every_step(name, slave, h) -> None:
    """Raise NotCompilable unless the sampled ``slave`` samples on every step (h = T,
    ``sample_phase`` 0, ``hold_first_step`` false): its kernel has no sub-step counter (:mod:`fmus.slave.sampling`), the
    Python path counts, holds, or refuses by name."""
    phase = getattr(slave, PHASE_PARAMETER)
    if substeps_of(slave.T, h) != 1 or phase != 0:
        raise NotCompilable(f"component {name}: steps h = {h!r} s with T = {slave.T!r} s, {PHASE_PARAMETER} = "
                            f"{phase!r}: the compiled kernel samples on every step (h = T, {PHASE_PARAMETER} 0 only)")
    if getattr(slave, HOLD_FIRST_PARAMETER, False):
        raise NotCompilable(f"component {name}: {HOLD_FIRST_PARAMETER} = True: the compiled kernel samples on the "
                            "first step too")


@register
class TrajectoryAdapter(Adapter):
    """``pc_trajectory_io``: the reference at the step's end."""

    model = "Trajectory"
    outputs = ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d", "x_start", "y_start")
    kernel = "pc_trajectory_io"

    def context(self):
        return trajectories.kernel_context(self.slave.trajectory)


@register
class DerivatorAdapter(Adapter):
    """``pc_derivator_io``, inputs limited to |q| <= ABSURD as the slave."""

    model = "Derivator"
    inputs = ("q1", "q2")
    outputs = ("dq1", "dq2", "ddq1", "ddq2")
    kernel = "pc_derivator_io"

    def __init__(self, name, slave, h):
        super().__init__(name, slave, h)
        _samples_every_step(name, slave, h)

    def context(self):
        return derivators.kernel_context(self.slave.derivator, ABSURD)


@register
class PositionControllerAdapter(Adapter):
    """``pc_law_io`` (kernels/src/law.c) on the controller's buffers, the commands through the
    slave's delay queue.  The exact model's terms come from the 5R kernel's inverse terms,
    the context's terms function (``pc_fivebar_terms_of`` on the model's parameter buffer)."""

    model = "PositionController"
    inputs = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")
    outputs = ("tau1", "tau2", "i_ref1", "i_ref2", "e1", "e2")
    kernel = "pc_law_io"

    def __init__(self, name, slave, h):
        super().__init__(name, slave, h)
        _samples_every_step(name, slave, h)
        c = slave.controller
        if not c.compiled:
            raise NotCompilable(f"component {name}: the controller's kernel {c.kernel!r} is not compiled")
        self.controller, self.delayed = c, slave.delayed

    def refused(self, refusal, t):
        """The controller's own refusal (:meth:`controller.position.PositionController.step_with_errors`):
        the sample's inputs are still in ``x`` and the kernel's scratch is the controller's; None for
        what the Python controller finishes itself (the exact model's terms, a sample off the table
        with ``table_fallback``)."""
        c, code = self.controller, refusal.code
        if code == law.NEEDS_TERMS or (code in law.TABLE_CODES and c._fallback is not None):
            return None
        return c._refused(refusal, t, tuple(self.x[:len(self.inputs)].tolist()))

    def context(self):
        c = self.controller
        exact = c.model_kind == "exact"
        self._context = law.loop_context(c._binding(), self.delayed, ctypes.c_void_p(TERMS_OF) if exact else None)
        if exact:
            self._model = c.model._p        # the parameters the terms function reads, kept alive
            self._context.model = kernels.address(self._model)
        return self._context


@register
class CurrentObserverAdapter(Adapter):
    """``pc_observer_io`` (kernels/src/observer.c) on the slave's observer buffer."""

    model = "CurrentObserver"
    inputs = ("v", "omega")
    outputs = ("i_hat",)
    kernel = "pc_observer_io"

    def __init__(self, name, slave, h):
        super().__init__(name, slave, h)
        _samples_every_step(name, slave, h)
        slave.observer.prepare_step(h)
        self.buffers = [slave.observer.buf]

    def context(self):
        from motor.kernel import ObserverContext

        self._context = ObserverContext(kernels.address(self.buffers[0]))
        return self._context


def _prepared(name, drive, h):
    try:
        drive.prepare_step(h)
    except ValueError as exc:
        raise NotCompilable(f"component {name}: {exc}") from None
    return [drive.buf, drive._controller_buf]


@register
class DCMotorDriveAdapter(Adapter):
    """``pc_drive_io`` (kernels/src/drive.c) on the slave's drive buffers: the drive, its
    controller and, with LuGre friction, its bristles (advanced with the step, as ``Drive.step``)."""

    model = "DCMotorDrive"
    inputs = ("i_ref", "v_ref", "omega", "i_hat")
    outputs = ("tau", "v", "i")
    kernel = "pc_drive_io"

    def __init__(self, name, slave, h):
        super().__init__(name, slave, h)
        drive = slave.drive
        self.buffers = _prepared(name, drive, h) + [drive.lugre]

    def context(self):
        from motor.kernel import DriveContext

        self._context = DriveContext(*(None if b is None else kernels.address(b) for b in self.buffers))
        return self._context


def _check_plant(name, sim, h) -> None:
    """Raise NotCompilable unless ``sim``'s step at h is the C kernel's (its settings buffer,
    ``sim._fast.s``, is then the compiled loop's)."""
    from plant.simulator import PlantError

    s = sim.settings
    if s.method != "rk4" or s.kernel != "fast" or s.project:
        raise NotCompilable(f"component {name}: the plant's settings method={s.method!r}, kernel={s.kernel!r}, "
                            f"project={s.project!r} are not compiled (rk4, fast, no projection are)")
    try:
        sim.check_step(h)
    except PlantError as exc:
        raise NotCompilable(f"component {name}: {exc}") from None


class _PlantState(Adapter):
    """The plant's state lives in ``self.state`` while compiled (the simulator replaces its
    array every step): copied to and from the simulator around a Python step."""

    def _sim(self):
        raise NotImplementedError

    def to_python(self):
        sim = self._sim()
        sim.y = self.state[:14].copy()
        sim._last = None

    def from_python(self):
        self.state[:14] = self._sim().y


@register
class FiveBarPlantAdapter(_PlantState):
    """``pc_fivebar_plant_io`` (kernels/src/fivebar.c) on the adapter's copy of the state."""

    model = "FiveBarPlant"
    inputs = ("tau1", "tau2")
    outputs = _PLANT_OUTPUTS
    kernel = "pc_fivebar_plant_io"

    def __init__(self, name, slave, h):
        super().__init__(name, slave, h)
        if slave.idle_steps:
            raise NotCompilable(f"component {name}: idle steps (a model inside a controller)")
        sim = slave.sim
        _check_plant(name, sim, h)
        self.state = sim.y.copy()
        self._context = sim._fast.context(self.state)

    def _sim(self):
        return self.slave.sim

    def refused(self, refusal, t):
        """The plant's own refusal (:meth:`plant.simulator.PlantSimulator.kernel_refusal`): the
        torques are still in ``x``, the trial state in the context's scratch."""
        sim = self.slave.sim
        sim.time = t                 # as the slave's step sets it
        tau1, tau2 = self.x[:2].tolist()
        trial = self._context.buffers[-1][:len(self.state)].copy()
        return sim.kernel_refusal(tau1, tau2, self.h, refusal.code, refusal, trial)

    def context(self):
        return self._context


@register
class ActuatedFiveBarPlantAdapter(_PlantState):
    """``pc_actuated_io`` (kernels/src/actuated.c): both drives' voltage samples, the LuGre
    bristles, the plant's actuated step, then the drives kept; nothing changes unless the
    whole step is accepted."""

    model = "ActuatedFiveBarPlant"
    inputs = ("i_ref1", "i_hat1", "v_ref1", "i_ref2", "i_hat2", "v_ref2")
    outputs = _PLANT_OUTPUTS + ("tau1", "tau2", "v1", "v2", "i1", "i2")
    kernel = "pc_actuated_io"

    def __init__(self, name, slave, h):
        from plant.simulator import PlantError

        super().__init__(name, slave, h)
        a = slave.actuated
        if slave.idle_steps:
            raise NotCompilable(f"component {name}: idle steps (a model inside a controller)")
        if [j for j, _ in a.drives] != [1, 2]:
            raise NotCompilable(f"component {name}: drives on joints {[j for j, _ in a.drives]} (1 and 2 are compiled)")
        _check_plant(name, a.plant, h)
        try:
            a._check_rk4_stability(h, a.plant.settings.substeps)
        except PlantError as exc:
            raise NotCompilable(f"component {name}: {exc}") from None
        for _, drive in a.drives:
            _prepared(name, drive, h)
        self.state = a.state()
        self._context = actuated_context(a, self.state, len(self.inputs))

    def _sim(self):
        return self.slave.actuated.plant

    def refused(self, refusal, t):
        """The plant's own refusal (:meth:`plant.actuated.ActuatedPlant.kernel_refusal`): the drives'
        inputs are still in ``x``, the trial state in the plant context's scratch."""
        a = self.slave.actuated
        a.plant.time = t             # as the slave's step sets it
        i_ref1, i_hat1, v_ref1, i_ref2, i_hat2, v_ref2 = self.x[:len(self.inputs)].tolist()
        trial = self._context.buffers[0].buffers[-1][:len(self.state)].copy()
        return a.kernel_refusal(refusal.code, refusal, trial, (i_ref1, i_ref2), (i_hat1, i_hat2), (v_ref1, v_ref2),
                                self.h)

    def from_python(self):
        super().from_python()
        for n, (_, drive) in enumerate(self.slave.actuated.drives):
            self.state[14 + n] = drive.i

    def context(self):
        return self._context


@register
class BalanceControllerAdapter(Adapter):
    """``pc_balance_io`` on the controller's own buffer, inputs limited to |x| <= ABSURD as the slave."""

    model = "BalanceController"
    inputs, outputs = fastbalance.INPUTS, fastbalance.OUTPUTS
    kernel = "pc_balance_io"

    def __init__(self, name, slave, h):
        super().__init__(name, slave, h)
        _samples_every_step(name, slave, h)
        self.buf = slave.controller.buf

    def context(self):
        self._context = fastbalance.Context(kernels.address(self.buf), ABSURD)
        return self._context


@register
class WheeledPendulumAdapter(Adapter):
    """``pc_wheeled_io`` on the simulator's own parameter and state buffers (the kernel
    changes the state only when the whole step is accepted: a fall is re-run by the Python
    path, which raises it)."""

    model = "WheeledPendulum"
    inputs = wheeled_kernel.INPUT_NAMES
    outputs = wheeled_kernel.OUTPUT_NAMES
    kernel = "pc_wheeled_io"

    def __init__(self, name, slave, h):
        super().__init__(name, slave, h)
        sim = slave.sim
        self.settings = wheeled_kernel.new_settings(substeps=sim.substeps, count=sim.count, limit=ABSURD,
                                                    push_torque=slave.push_torque, push_start=slave.push_start,
                                                    push_duration=slave.push_duration)
        self.buffers = (sim.prm, sim.y, self.settings)

    def context(self):
        self._context = wheeled_kernel.Context(*(kernels.address(b) for b in self.buffers))
        return self._context
