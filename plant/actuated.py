"""The plant with its drives' armature circuits: one ODE, the monolithic plant-motor coupling.

The co-simulation's bench couples each :class:`motor.Drive` to the plant at the
communication step: the drive integrates its current with the shaft speed held and the
plant holds the drive's torque.  :class:`ActuatedPlant` removes that coupling: the state

    z = [q (7), dq (7), i_1, ..., i_n]

(the thesis' coordinates 7.12 and the drives' armature currents) is integrated as one ODE:

* dq/dt from the forward dynamics (5.66) with, on each driven joint, the shaft torque
  kt i - b omega - mu tanh(omega / omega_eps) of the present current and speed (B.2,
  :func:`motor.shaft_torque`);
* L di/dt = v - R i - ke omega (4.162, :func:`motor.armature_current_rate`), v the voltage
  the drive's discrete current controller holds over the step
  (:meth:`motor.Drive.sample_voltage`).

What stays discrete is the drives' own: each controller samples i_ref and i_hat at the
step's start (zero-order hold), as in the separate drive.  So does a drive's LuGre friction
(``friction="lugre"``, :mod:`motor.friction`): its bristle state advances over the step with
the joint speed at the step's start held, exactly as in the separate drive, and the plant
holds the bristles' mean torque σ0 z + σ1 dz/dt over the step; the viscous part σ2 ω = b ω
stays in the ODE (docs/friction.md: the same coupling, the same stability band).  The bristle
deflection stays the drive's state (``drive.z``), like its current.  The plant's integrator
settings (:class:`plant.IntegratorSettings`: RK4 and its substeps, or dopri5 and its
tolerances) apply to the whole state, and its refusals (residual, singular pose) to the
mechanical part.
The monolithic reference (``scenarios/reference.py``) integrates this same
:meth:`ActuatedPlant.derivative` with scipy's DOP853 at rtol 1e-10.
"""
from __future__ import annotations

import ctypes
import math

import numpy as np

import kernels

from motor import armature_current_rate, friction, shaft_torque

from . import fast5r, fivebar
from .integrators import WorkLimitError
from .simulator import RK4_REAL_STABILITY, PlantError, PlantSimulator

_PAIR = ctypes.c_void_p * 2
#: ``pc_actuated_step(context, x, h, refusal)`` (kernels/src/actuated.h).
_step = kernels.function("pc_actuated_step", ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double,
                         ctypes.c_void_p)
#: Where the plant's outputs start in the step's x (after i_ref, i_hat, v_ref of each drive).
_FIRST = 6


class KernelContext(ctypes.Structure):
    """``pc_actuated_context`` (kernels/src/actuated.h): the buffers ``pc_actuated_io`` steps."""

    _fields_ = [("plant", ctypes.c_void_p), ("drive", _PAIR), ("controller", _PAIR), ("friction", _PAIR),
                ("bristles", _PAIR)]


def kernel_context(actuated, state, first: int) -> KernelContext:
    """A ``pc_actuated_context`` over ``actuated``'s (an :class:`ActuatedPlant` with drives on
    joints 1 and 2, each prepared for the step) plant kernel, ``state`` (z) and its drives'
    buffers; the plant's outputs start at x[first].  The context keeps every buffer alive."""
    plant = actuated.plant._fast.context(state, actuated._motors, first=first)
    drives = [d for _, d in actuated.drives]

    def addresses(buffers):
        return _PAIR(*(None if b is None else kernels.address(b) for b in buffers))

    context = KernelContext(ctypes.addressof(plant), addresses([d.buf for d in drives]),
                            addresses([d._controller_buf for d in drives]), addresses(actuated.lugre_models),
                            addresses([d.lugre if f is not None else None
                                       for d, f in zip(drives, actuated.lugre_models)]))
    context.buffers = (plant, drives, actuated.lugre_models)
    return context


class KernelStep:
    """The in-process step of an :class:`ActuatedPlant` with drives on joints 1 and 2: one call
    of ``pc_actuated_step`` on its own z and x arrays (:func:`kernel_context`), bound once."""

    def __init__(self, actuated):
        self.z = np.empty(fast5r.PLANT_STATES + 2)
        self.x = np.zeros(_FIRST + fast5r.PLANT_OUTPUT_COUNT + 6)
        self.context = kernel_context(actuated, self.z, _FIRST)
        self.trial = self.context.buffers[0].buffers[5]    # the plant's scratch: a refused trial state there
        self.refusal = kernels.Refusal()
        #: call(h) -> the status
        self.call = kernels.bind(_step, self.context, self.x, kernels.PER_CALL, self.refusal)


#: The plant's report of an accepted state as far as ``PlantSimulator.outputs`` reads it.
_OUTPUTS = slice(fast5r.REPORT_OUTPUTS, fast5r.REPORT_OUTPUTS + fast5r.PLANT_OUTPUT_COUNT - 1)


class ActuatedPlant:
    """A :class:`PlantSimulator` whose actuated joints are driven by drives it integrates.

    Parameters
    ----------
    plant : PlantSimulator
        The mechanism, its state and its integrator settings (used for the whole state).
    drives : sequence of (int, motor.Drive)
        (joint, drive) pairs: the drive delivers the world torque tau_joint and turns at
        dq_joint, joint 1 or 2, each at most once.  Every drive needs L > 0 (an armature
        current to integrate).  The drives keep their controllers, parameters and state:
        ``i`` (the current), ``v`` (the last voltage) and, with LuGre friction, the bristle
        deflection ``z`` (in ``drive.lugre``); this class updates them after each accepted
        step, so a drive reads as the drive inside the plant (``drive.z``, ``drive.torque``).

    Attributes
    ----------
    lugre_models : list of (ndarray or None)
        Per drive, the friction array (:func:`motor.friction.new_lugre`) of its LuGre
        parameters with σ2 = 0 (b ω is in the ODE), None for a tanh drive.  Parameters only:
        its deflection slot is NaN, the deflection is the drive's.
    """

    def __init__(self, plant: PlantSimulator, drives):
        self.plant = plant
        self.drives = tuple((int(j), d) for j, d in drives)
        joints = [j for j, _ in self.drives]
        if any(j not in (1, 2) for j in joints) or len(set(joints)) != len(joints):
            raise ValueError(f"drive joints must be 1 and/or 2, each at most once, got {joints}")
        for j, d in self.drives:
            if not d.params.L > 0.0:
                raise ValueError(f"drive on joint {j}: L = {d.params.L!r} H has no armature current to integrate "
                                 f"(use a separate drive with method 'quasi_static')")
        # A LuGre drive: no tanh term in the ODE (mu = 0 there), its bristle torque from the
        # drive's deflection and the parameters without b (b stays in the ODE).
        self._shaft = [d.params.with_(mu=0.0) if d.lugre is not None else d.params for _, d in self.drives]
        self.lugre_models = [friction.new_lugre(friction.LuGre.of_motor(d.params.with_(b=0.0)), math.nan)
                             if d.lugre is not None else None for _, d in self.drives]
        self._motors = np.array([[j - 1, p.R, p.L, p.kt, p.ke, p.b, p.mu, p.omega_eps]
                                 for (j, _), p in zip(self.drives, self._shaft)]).reshape(-1, fast5r.MOTOR_COLUMNS)
        self._stable_for = None     # the step RK4 was last found stable for
        s = plant.settings
        #: The step is one C call (:class:`KernelStep`): RK4 with the C kernel, no projection,
        #: both drives; otherwise the same kernels composed here (dopri5, the general kernel, ...).
        self._one_call = (s.method == "rk4" and plant._fast is not None and not s.project
                          and joints == [1, 2])

    @property
    def currents(self) -> list:
        """The armature currents [A], one per drive."""
        return [d.i for _, d in self.drives]

    def state(self) -> np.ndarray:
        """z = [q, dq, currents] (a new array)."""
        z = np.empty(14 + len(self.drives))
        z[:14] = self.plant.y
        for n, (_, d) in enumerate(self.drives):
            z[14 + n] = d.i
        return z

    def derivative(self, z, voltages, external=(0.0, 0.0), omega_held=None):
        """dz/dt with the drives' voltages and world torques ``external`` on (q1, q2) held.

        With the plant's C kernel, :func:`plant.fast5r.actuated_derivative`; with the general
        kernel (or ``omega_held``), the general algorithm's forward dynamics with the motors'
        equations added here.  ``omega_held`` (one speed per drive), a diagnostic of the
        reference, replaces the joint speed the drives see (back-emf and friction) by a held one.
        """
        fast = self.plant._fast
        if fast is not None and omega_held is None:
            u_star = fivebar.thesis_torques(*external)
            return fast.actuated_derivative(z, self._motors, np.asarray(voltages, dtype=float), u_star[0], u_star[1],
                                            self.plant.settings.baumgarte)
        y = z[:14]
        rates = fivebar.world_rates(y[7:])
        tau = list(external)
        dz = np.empty(len(z))
        for n, (j, drive) in enumerate(self.drives):
            omega = rates[j - 1] if omega_held is None else omega_held[n]
            tau[j - 1] += shaft_torque(z[14 + n], omega, self._shaft[n])
            dz[14 + n] = armature_current_rate(z[14 + n], voltages[n], omega, drive.params)
        dz[:14] = self.plant.derivative(y, fivebar.thesis_torques(tau[0], tau[1]))
        return dz

    def step(self, i_ref, i_hat, v_ref, dt: float, max_evaluations: int | None = None) -> int:
        """Advance by dt: each drive samples its voltage (:meth:`motor.Drive.sample_voltage`
        with ``i_ref[n]``, ``i_hat[n]``, ``v_ref[n]``), held over the step, and the whole
        state is integrated; returns the right-hand-side evaluations taken.  Refused, the state
        and the controllers kept: ValueError naming the input with its joint (e.g. ``i_ref2``)
        when one is not finite; :class:`plant.PlantError` for the plant's reasons, for RK4 steps
        beyond the stability of the electrical pole (R h / L > 2.785), and for non-finite
        currents; :class:`plant.integrators.WorkLimitError` when dopri5 reaches
        ``max_evaluations``.
        """
        plant = self.plant
        plant.check_step(dt)
        s = plant.settings
        if s.method == "rk4" and dt != self._stable_for:
            self._check_rk4_stability(dt, s.substeps)
        if self._one_call:
            return self._step_in_c(i_ref, i_hat, v_ref, dt)
        self._check_inputs(i_ref, i_hat, v_ref)
        # With a work limit (dopri5) the step may stop unfinished: the controllers go back too.
        snapshots = None if max_evaluations is None else [d.controller_state() for _, d in self.drives]
        voltages = [d.sample_voltage(i_ref[n], v_ref[n], i_hat[n], dt) for n, (_, d) in enumerate(self.drives)]
        try:
            return self.advance(voltages, dt, max_evaluations)
        except WorkLimitError:
            for (_, d), snapshot in zip(self.drives, snapshots):
                d.restore_controller_state(snapshot)
            raise

    def _check_inputs(self, i_ref, i_hat, v_ref) -> None:
        """Refuse (ValueError naming it with its joint, e.g. ``i_ref2``) an input that is not finite."""
        for name, values in (("i_ref", i_ref), ("i_hat", i_hat), ("v_ref", v_ref)):
            for (j, _), value in zip(self.drives, values):   # all before any controller samples
                if not math.isfinite(value):
                    raise ValueError(f"input {name}{j} = {value!r} is not finite")

    def _step_in_c(self, i_ref, i_hat, v_ref, dt: float) -> int:
        """:meth:`step` as one ``pc_actuated_step`` (:class:`KernelStep`): RK4 with the C kernel,
        no projection, drives on joints 1 and 2.  A refusal changes nothing."""
        plant, ((_, d1), (_, d2)) = self.plant, self.drives
        d1.prepare_step(dt)
        d2.prepare_step(dt)
        k = kernels.owned(self, (d1.buf, d1._controller_buf, d1.lugre, d2.buf, d2._controller_buf, d2.lugre),
                          lambda *_: KernelStep(self))
        x, z = k.x, k.z
        x[:_FIRST] = (i_ref[0], i_hat[0], v_ref[0], i_ref[1], i_hat[1], v_ref[1])
        z[:fast5r.PLANT_STATES] = plant.y
        z[fast5r.PLANT_STATES:] = d1.i, d2.i
        status = k.call(dt)
        if status != fast5r.OK:
            raise self.kernel_refusal(status, k.refusal, k.trial[:k.z.size].copy(), i_ref, i_hat, v_ref, dt)
        outputs = x[_FIRST:_FIRST + fast5r.PLANT_OUTPUT_COUNT].tolist()   # ..., q2_enc, residual
        report = [0.0] * fast5r.REPORT_SIZE     # what PlantSimulator.outputs reads; the rest 0
        report[_OUTPUTS], report[fast5r.REPORT_RESIDUAL] = outputs[:-1], outputs[-1]
        plant.accept(z[:fast5r.PLANT_STATES].copy(), dt, None, (fast5r.OK, 0, outputs[-1], report))
        return 4 * plant.settings.substeps

    def kernel_refusal(self, status: int, r, trial, i_ref, i_hat, v_ref, dt: float) -> Exception:
        """The refusal of a ``pc_actuated_step`` from the present state that returned ``status``
        with its refusal ``r`` (index, value) and left its trial state (plant and currents) in
        ``trial``, with :meth:`advance`'s messages (the voltages held named as the drives would
        have sampled them).  The compiled loop makes the refusal of a step its kernel declined
        with it too."""
        try:
            return self._kernel_refusal(status, r, trial, i_ref, i_hat, v_ref, dt)
        except ValueError as exc:     # PlantError, a drive's input named: raised where each is found
            return exc

    def _kernel_refusal(self, status, r, trial, i_ref, i_hat, v_ref, dt):
        if status == fast5r.NONFINITE_INPUT:
            self._check_inputs(i_ref, i_hat, v_ref)     # a drive's input: named as ever
        snapshots = [d.controller_state() for _, d in self.drives]
        voltages = [d.sample_voltage(i_ref[n], v_ref[n], i_hat[n], dt) for n, (_, d) in enumerate(self.drives)]
        for (_, d), snapshot in zip(self.drives, snapshots):
            d.restore_controller_state(snapshot)
        plant = self.plant

        def held():
            return self._held_text(voltages)

        if status == fast5r.NONFINITE_INPUT:
            raise plant._record(f"integration failed in the step from t = {plant.time:.6g} s ({held()}): the held "
                                f"input {r.index} = {r.value!r} is not finite", status, f"input {r.index}", r.value,
                                plant.time)
        if status == fast5r.NONFINITE_STATE and r.index >= fast5r.PLANT_STATES:
            raise self._currents_refusal(trial[fast5r.PLANT_STATES:].tolist(), held)
        plant.accept(trial[:fast5r.PLANT_STATES], dt, held, (status, r.index, r.value, None))

    def _held_text(self, voltages) -> str:
        return ", ".join(f"v{j} = {v!r} V" for (j, _), v in zip(self.drives, voltages)) + " held"

    def _currents_refusal(self, currents: list, held):
        """The refusal of a step whose armature ``currents`` are not all finite."""
        plant = self.plant
        bad = next(n for n, i in enumerate(currents) if not math.isfinite(i))
        return plant._record(f"armature currents {currents} after the step from t = {plant.time:.6g} s "
                             f"({held()}) are not finite", fast5r.NONFINITE_STATE, f"i{self.drives[bad][0]}",
                             currents[bad], plant.time)

    def advance(self, voltages, dt: float, max_evaluations: int | None = None) -> int:
        """Integrate the whole state over dt with the drives' ``voltages`` held (the part of
        :meth:`step` after the controllers sampled); each drive's ``v`` becomes its voltage.
        Returns the right-hand-side evaluations taken.  Refused as :meth:`step`, the state kept."""
        plant = self.plant

        def held():
            return self._held_text(voltages)

        external, bristles = self.held_friction(dt)
        u_star = fivebar.thesis_torques(*external) if any(b is not None for b in bristles) else (0.0, 0.0)
        z, verdict, evaluations = plant.integrate(self.state(), dt, u_star[0], u_star[1], held,
                                                 lambda w: self.derivative(w, voltages, external),
                                                 self._motors, np.array(voltages, dtype=float), max_evaluations)
        currents = z[14:].tolist()
        if not all(map(math.isfinite, currents)):
            raise self._currents_refusal(currents, held)
        plant.accept(z[:14], dt, held, verdict)
        for (_, d), i, v, b in zip(self.drives, currents, voltages, bristles):
            d.i, d.v = i, v
            if b is not None:
                d.z = b
        return evaluations

    def held_friction(self, dt: float):
        """(world torques on (q1, q2), new bristle deflections): minus each LuGre drive's mean
        bristle torque over the next dt from its deflection, the joint speed held
        (:func:`motor.friction.advance`; the speed is finite: the plant accepts no other state)."""
        rates = fivebar.world_rates(self.plant.y[7:])
        external, bristles = [0.0, 0.0], []
        for (j, d), f in zip(self.drives, self.lugre_models):
            if f is None:
                bristles.append(None)
                continue
            z, _, f_mean = friction.advance(f, d.z, rates[j - 1], dt)
            external[j - 1] -= f_mean
            bristles.append(z)
        return external, bristles

    def _check_rk4_stability(self, dt, substeps):
        """Refuse RK4 sub-steps beyond the stability of an electrical pole -R/L."""
        h = dt / substeps
        for j, d in self.drives:
            x = d.params.R * h / d.params.L
            if x > RK4_REAL_STABILITY:
                raise PlantError(
                    f"drive on joint {j}: RK4 steps of {h:.6g} s are unstable for its armature circuit: "
                    f"R h / L = {x:.4g} > {RK4_REAL_STABILITY:.4g} (L/R = {d.params.L / d.params.R:.3g} s); "
                    f"use substeps >= {math.ceil(dt * d.params.R / (d.params.L * 2.0))} or dopri5")
        self._stable_for = dt

    def shaft_torques(self) -> list:
        """Each drive's shaft torque at the present current and joint speed [N m] (B.2)."""
        rates = fivebar.world_rates(self.plant.y[7:])
        torques = []
        for (j, d), params, f in zip(self.drives, self._shaft, self.lugre_models):
            tau = shaft_torque(d.i, rates[j - 1], params)
            if f is not None:
                tau -= friction.friction_force(f, d.z, rates[j - 1])
            torques.append(tau)
        return torques
