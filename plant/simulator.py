"""Time stepping of the 5R plant over communication steps.

:class:`PlantSimulator` holds the mutable state (the thesis' q and dq,
7.12) of an immutable mechanism and advances it over a communication step
with the actuator torques held.  The FMU slave, the in-process master and
the benchmarks all step the plant through this class.

Two evaluation kernels compute the same forward dynamics (5.66):

``general``
    :func:`plant.parallel.forward_dynamics`, the thesis' algorithm for any
    DH chains and architecture matrices, in numpy.  The source of truth.
``fast``
    :mod:`plant.fast5r`, the same equations specialised to planar RR chains
    in C (``kernels/src/fivebar.c``); tested against ``general`` to round-off.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import kernels

from . import fast5r, fivebar
from .integrators import IntegrationError, WorkLimitError, dopri5, rk4
from .parallel import left_inverse_solve, mechanism_state, forward_dynamics
from .presets import FiveBarParams

METHODS = ("rk4", "dopri5")
KERNELS = ("fast", "general")


@dataclass(frozen=True)
class IntegratorSettings:
    """How the plant is integrated over one communication step.

    Parameters
    ----------
    method : {"rk4", "dopri5"}
        Fixed-step RK4 with ``substeps`` steps, or adaptive Dormand-Prince
        5(4) with tolerances ``rtol``/``atol``.
    substeps : int
        RK4 steps per communication step.
    rtol, atol : float
        Tolerances of ``dopri5``.
    baumgarte : float
        Baumgarte lambda [1/s] of (5.66).  10/s is far below the thesis'
        upper bound 1/h; measured against 0 and 100/s it gave the smallest
        end-effector error and residual (docs/plant.md).
    project : bool
        After each communication step, put q and dq back on the constraint
        manifold by Newton steps on q̄(q) = 0 and dq = C(q) dq#, keeping the
        independent coordinates q# = (x, y).  Off by default: it zeroes the
        residual but, near serial singularities, (A Q°)^-1 amplifies the
        integration error of (x, y) into the angles (measured 1e4x larger
        end-effector error on fast motions, docs/plant.md).
    kernel : {"fast", "general"}
        Which implementation of (5.66) evaluates the accelerations.
    """

    method: str = "rk4"
    substeps: int = 1
    rtol: float = 1e-10
    atol: float = 1e-13
    baumgarte: float = 10.0
    project: bool = False
    kernel: str = "fast"

    def validate(self) -> "IntegratorSettings":
        if self.method not in METHODS:
            raise ValueError(f"method: unknown integrator {self.method!r}; valid: {', '.join(METHODS)}")
        if self.kernel not in KERNELS:
            raise ValueError(f"kernel: unknown kernel {self.kernel!r}; valid: {', '.join(KERNELS)}")
        if not (isinstance(self.substeps, int) and 1 <= self.substeps <= MAX_SUBSTEPS):
            raise ValueError(f"substeps must be an integer in [1, {MAX_SUBSTEPS}], got {self.substeps!r}")
        for name in ("rtol", "atol"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be > 0, got {value!r}")
        if not (math.isfinite(self.baumgarte) and self.baumgarte >= 0.0):
            raise ValueError(f"baumgarte must be >= 0, got {self.baumgarte!r}")
        return self


#: Upper bound of ``substeps``: 0.1 µs RK4 steps at the 1 ms communication step.
MAX_SUBSTEPS = 10000
#: RK4's stability interval on the negative real axis: |R(z)| <= 1 for -2.785... <= z <= 0.
#: The Baumgarte term gives the residual a double pole at -baumgarte (5.66), so an RK4 step h
#: with baumgarte * h beyond it makes the residual grow at every step.
RK4_REAL_STABILITY = 2.785293563405282
#: Largest baumgarte * h accepted with RK4.  Beyond 2 RK4's factor on the residual per step,
#: |R(-baumgarte h)|, rises from 1/3 to 1 (instability at 2.785), and the end-effector error
#: with it: 2.7e-6 m at 2, 4.5e-5 m at 2.5, 7.8e-3 m at 2.7 (docs/extremes.md).
BAUMGARTE_RK4_LIMIT = 2.0
#: A loop-closure residual (5.18) above this after a step means the integration diverged:
#: the state no longer describes the closed mechanism (in normal runs it is ~1e-10 m).
RESIDUAL_STOP = 1e-3

#: Settings that reach ~1e-9 m against an independent reference (see docs/plant.md).
ACCURATE = IntegratorSettings(method="dopri5", rtol=1e-12, atol=1e-15, project=False)


class PlantError(RuntimeError):
    """The plant cannot go on: singular pose, non-finite input or state."""


class PlantRefused(PlantError, kernels.Refused):
    """A step the plant refused, as the kernels' refusal record (:class:`kernels.Refused`:
    variable, value, unit, time, code, reason) with the message of its :class:`PlantError`."""

    def __init__(self, message: str, **record):
        kernels.Refused.__init__(self, message, **record)


#: What the 5R kernel's refusal codes name: (reason, unit) and, for SINGULAR, the measure of
#: each index (pc_fivebar_report.measures).
REFUSALS = {fast5r.NONFINITE_INPUT: ("nonfinite_input", "N m"), fast5r.NONFINITE_STATE: ("nonfinite_state", ""),
            fast5r.DIVERGED: ("diverged", "m"), fast5r.SINGULAR: ("singular", "")}
MEASURES = ("chain 1 elbow (serial)", "chain 2 elbow (serial)", "distal links (parallel)")


#: Below this singularity margin the step is refused: the mechanism is at a
#: singular pose where its dynamics (5.66) lose rank.
SINGULAR_STOP = 1e-3
#: Encoder counts per revolution of the thesis' bench (Table 5: 5000 pulses, quadrature).
ENCODER_COUNTS = 20000


class PlantSimulator:
    """The 5R plant: immutable model, mutable state.

    Parameters
    ----------
    params : FiveBarParams
    x0, y0 : float
        Start with the end effector there (working mode).
    dx0, dy0 : float
        Initial end-effector velocity (default: at rest).
    settings : IntegratorSettings
    encoder_counts : int
        Counts per revolution of the encoders (quadrature: 4x the pulses).
    encoder_offsets : (float, float)
        Zero errors of the two encoders [rad]: ``q<k>_enc`` reads q_k + offset, quantised
        (a robot homed slightly off; the controller does not know it).
    """

    def __init__(self, params: FiveBarParams, x0: float, y0: float,
                 settings: IntegratorSettings = IntegratorSettings(), encoder_counts: int = ENCODER_COUNTS,
                 dx0: float = 0.0, dy0: float = 0.0, encoder_offsets=(0.0, 0.0)):
        self.params = params.validate()
        self.settings = settings.validate()
        if not (isinstance(encoder_counts, int) and encoder_counts > 0):
            raise ValueError(f"encoder_counts must be a positive integer, got {encoder_counts!r}")
        self.encoder_counts = encoder_counts
        self.count = 2.0 * math.pi / encoder_counts    # one encoder count [rad]
        self.encoder_offsets = tuple(float(e) for e in encoder_offsets)
        if len(self.encoder_offsets) != 2 or not all(math.isfinite(e) for e in self.encoder_offsets):
            raise ValueError(f"encoder_offsets must be 2 finite numbers [rad], got {encoder_offsets!r}")
        self.mechanism = fivebar.build_mechanism(params)
        self.time = 0.0
        try:
            q = fivebar.thesis_coordinates(params, x0, y0)
        except fivebar.KinematicsError as exc:
            raise ValueError(f"start point x0={x0!r}, y0={y0!r}: {exc}") from None
        margin = fivebar.singularity(params, x0, y0).margin
        if margin < SINGULAR_STOP:
            raise ValueError(f"start point x0={x0!r}, y0={y0!r} is singular (margin {margin:.3g})")
        C = mechanism_state(self.mechanism, q, np.zeros(7)).C
        self.y = np.concatenate([q, C @ np.array([dx0, dy0], dtype=float)])
        self._h_next = None
        # (state, its residual norm, the compiled step's report or None) after the last step
        self._last = None
        self._fast = None
        s = self.settings
        #: A step is one C step (:meth:`_kernel_step`): RK4 with the C kernel, no projection.
        self._one_call = s.method == "rk4" and s.kernel == "fast" and not s.project
        self._evaluations = 4 * s.substeps
        self._accepted_step = None    # the step length last found good (check_step)
        if self.settings.kernel == "fast":
            s = self.settings
            self._fast = fast5r.FastKernel(params, fast5r.pack_settings(
                s.baumgarte, s.substeps, self.count, RESIDUAL_STOP, SINGULAR_STOP, self.encoder_offsets))

    # --- derivatives -----------------------------------------------------------
    def derivative(self, y, u_star):
        """dy/dt for y = [q, dq] with actuator efforts u* on (theta11, theta21)."""
        if self._fast is not None:
            return self._fast.derivative(y, u_star, self.settings.baumgarte)
        q, dq = y[:7], y[7:]
        ddq = forward_dynamics(self.mechanism, q, dq, u_star, self.settings.baumgarte)
        return np.concatenate([dq, ddq])

    # --- stepping ----------------------------------------------------------------
    def step(self, tau1: float, tau2: float, dt: float, max_evaluations: int | None = None) -> int:
        """Advance by dt with the world torques held; the state is kept on error.  Returns the
        right-hand-side evaluations it took (4 per RK4 substep; dopri5's own count).

        Refused (:class:`PlantError`, naming the cause): a non-finite torque or step, a
        Baumgarte lambda above :data:`BAUMGARTE_RK4_LIMIT` / h for the RK4 step h, an integration
        that fails or diverges (non-finite state, or loop-closure residual above
        :data:`RESIDUAL_STOP`; the message gives the torques held), a singular pose.  dopri5
        stops at ``max_evaluations`` (None: unbounded) with :class:`plant.integrators.WorkLimitError`.
        """
        if self._one_call:
            return self._kernel_step(tau1, tau2, dt)
        self._check_torques(tau1, tau2)
        self.check_step(dt)

        def held():
            return f"tau1 = {tau1!r}, tau2 = {tau2!r} N m held"

        u_star = fivebar.thesis_torques(tau1, tau2)     # once: held over every derivative call of the step
        y, verdict, evaluations = self.integrate(self.y, dt, u_star[0], u_star[1], held,
                                                 lambda z: self.derivative(z, u_star), max_evaluations=max_evaluations)
        self.accept(y, dt, held, verdict)
        return evaluations

    def _check_torques(self, tau1, tau2) -> None:
        """Refuse (:class:`PlantRefused`, naming it) a torque that is not finite."""
        if not (math.isfinite(tau1) and math.isfinite(tau2)):
            name, value = ("tau1", tau1) if not math.isfinite(tau1) else ("tau2", tau2)
            raise self._record(f"input {name} = {value!r} at t = {self.time:.6g} s is not finite",
                               fast5r.NONFINITE_INPUT, name, value, self.time)

    def _kernel_step(self, tau1, tau2, dt: float) -> int:
        """:meth:`step` as one C step (RK4, the C kernel, no projection): u* = (tau1, -tau2)
        (fivebar.thesis_torques) straight to the kernel, which refuses a non-finite one first;
        a step length once accepted is not checked again (it depends on the settings alone)."""
        if dt != self._accepted_step:
            self._check_torques(tau1, tau2)     # as ever, a torque is named before the step
            self.check_step(dt)
            self._accepted_step = dt
        fast = self._fast
        status = fast.step(self.y, tau1, -tau2, dt)
        if status != fast5r.OK:
            raise self.kernel_refusal(tau1, tau2, dt, status, fast.refusal, fast.scratch[:fast5r.PLANT_STATES].copy())
        y = fast.scratch[:fast5r.PLANT_STATES].copy()
        report = fast.report.tolist()
        self.y = y
        self._last = (y, report[fast5r.REPORT_RESIDUAL], report)
        self.time += dt
        return self._evaluations

    def kernel_refusal(self, tau1, tau2, dt: float, status: int, refusal, trial) -> PlantRefused:
        """The refusal of a C kernel step from the present state, tau1, tau2 held over dt, that
        returned ``status`` with its ``refusal`` (index, value) and left its trial state in
        ``trial``: a non-finite torque named first, as :meth:`step` names it.  The compiled loop
        makes the refusal of a step its kernel declined with it too."""
        try:
            self._check_torques(tau1, tau2)
        except PlantRefused as exc:
            return exc

        def held():
            return f"tau1 = {tau1!r}, tau2 = {tau2!r} N m held"

        return self._refusal(status, refusal.index, refusal.value, trial, dt, held)

    def integrate(self, z, dt: float, u1: float, u2: float, held, derivative,
                  motors=fast5r.NO_MOTORS, voltages=fast5r.NO_VOLTAGES, max_evaluations: int | None = None):
        """Integrate ``z`` over dt with the settings; return (z at the end, the C kernel's verdict
        or None, the right-hand-side evaluations taken).

        ``z`` is the plant's state, followed by the currents of ``motors`` when a plant with
        drives calls (:class:`plant.actuated.ActuatedPlant`: rows of
        :data:`plant.fast5r.MOTOR_COLUMNS`, their ``voltages`` held).  (u1, u2) are the efforts
        held on theta11, theta21.  The C kernel integrates when it can (RK4; with no
        projection it also judges the new state: the verdict (status, index, value, report as
        a list, :data:`plant.fast5r.REPORT`) for :meth:`accept`); ``derivative(z)`` serves the
        general kernel and dopri5.  A failed integration is a :class:`PlantError` naming ``held()``;
        dopri5 stops at ``max_evaluations`` with :class:`plant.integrators.WorkLimitError`,
        nothing changed.
        """
        s = self.settings
        rk4_evaluations = 4 * s.substeps
        try:
            if s.method == "rk4" and self._fast is not None and not s.project:
                return (*self._fast_step(z, u1, u2, dt, held, motors, voltages), rk4_evaluations)
            if s.method == "rk4" and self._fast is not None:
                return self._fast.advance(z, u1, u2, s.baumgarte, dt, s.substeps, motors, voltages), None, \
                    rk4_evaluations
            if s.method == "rk4":
                return rk4(derivative, z, dt, s.substeps), None, rk4_evaluations
            z, h_next, _, evaluations = dopri5(derivative, z, dt, s.rtol, s.atol, self._h_next,
                                               max_evaluations=max_evaluations)
            self._h_next = h_next
            return z, None, evaluations
        except WorkLimitError:
            raise
        except (IntegrationError, np.linalg.LinAlgError) as exc:
            raise kernels.timed(PlantError(f"integration failed in the step from t = {self.time:.6g} s ({held()}): "
                                           f"{exc}")) from None

    def _fast_step(self, z, u1, u2, dt, held, motors, voltages):
        """The C kernel's RK4 step from z: (the trial state, a new array; the verdict)."""
        fast = self._fast
        status = fast.step(z, float(u1), float(u2), float(dt), motors, voltages)
        r = fast.refusal
        if status == fast5r.NONFINITE_INPUT:    # (u1, u2, voltages): the callers' checks come first
            raise self._record(f"integration failed in the step from t = {self.time:.6g} s ({held()}): the held "
                               f"input {r.index} = {r.value!r} is not finite", status, f"input {r.index}", r.value,
                               self.time)
        return fast.scratch[:z.size].copy(), (status, r.index, r.value, fast.report.tolist())

    def check_step(self, dt: float) -> None:
        """Refuse (:class:`PlantError`) a step length that is not finite and > 0, or a Baumgarte
        lambda above :data:`BAUMGARTE_RK4_LIMIT` / h for the RK4 step h."""
        if not (math.isfinite(dt) and dt > 0.0):
            raise kernels.timed(PlantError(f"step size {dt!r} at t = {self.time:.6g} s must be > 0"))
        s = self.settings
        if s.method == "rk4" and s.baumgarte * dt / s.substeps > BAUMGARTE_RK4_LIMIT:
            h = dt / s.substeps
            raise kernels.timed(PlantError(
                f"baumgarte = {s.baumgarte!r} /s with RK4 steps of {h:.6g} s (step from t = {self.time:.6g} s): "
                f"baumgarte * h = {s.baumgarte * h:.4g} > {BAUMGARTE_RK4_LIMIT:g}, RK4 no longer damps the "
                f"loop-closure residual (unstable beyond {RK4_REAL_STABILITY:.4g}); use baumgarte <= "
                f"{BAUMGARTE_RK4_LIMIT / h:.4g} /s (the thesis advises <= 1/h), more substeps or dopri5"))

    def accept(self, y, dt: float, held, verdict=None) -> None:
        """Make ``y``, the state integrated over dt from the present one, the new state.

        Projects it if the settings say so, then refuses it (:class:`PlantError`, the state
        kept; ``held()`` names the inputs held over the step) when it is not finite, does not
        close the loop (residual above :data:`RESIDUAL_STOP`) or is singular.  ``verdict``,
        from the C kernel's step (:meth:`integrate`, without projection), gives those checks'
        outcome and the outputs already computed; without it they run here.
        """
        if verdict is None:
            if self.settings.project and math.isfinite(float(y.sum())):
                y = self.project(y)
            status, index, value, report = self._judge(y)
        else:
            status, index, value, report = verdict
        if status != fast5r.OK:
            raise self._refusal(status, index, value, y, dt, held)
        residual = report[fast5r.REPORT_RESIDUAL] if report is not None else value
        self.y = y
        self._last = (y, residual, report)
        self.time += dt

    def _judge(self, y):
        """(status, index, value, None) of the state y as the C kernel judges it
        (fivebar.c: judge); the value of an accepted state is its residual."""
        if not math.isfinite(float(y.sum())):
            return fast5r.NONFINITE_STATE, 0, math.nan, None
        residual = self._residual_of(y)
        if not residual <= RESIDUAL_STOP:
            return fast5r.DIVERGED, 0, residual, None
        for k, value in enumerate(self._measures_of(y)):
            if abs(value) < SINGULAR_STOP:
                return fast5r.SINGULAR, k, value, None
        return fast5r.OK, 0, residual, None

    def _refusal(self, status, index, value, y, dt, held) -> PlantRefused:
        """The refusal record of a refused step's status (the one text of each reason)."""
        t = self.time
        if status == fast5r.NONFINITE_STATE:
            message = f"state became non-finite in the step from t = {t:.6g} s ({held()})"
            return self._record(message, status, f"state[{index}]", value, t)
        if status == fast5r.DIVERGED:
            s = self.settings
            message = (f"integration diverged in the step from t = {t:.6g} s ({held()}): loop-closure "
                       f"residual {value:.3g} m > {RESIDUAL_STOP:g} m, the state no longer closes the loop "
                       + (f"(motion too fast for RK4 steps of {dt / s.substeps:.3g} s: check the torques, use "
                          f"substeps or dopri5)" if s.method == "rk4" else "(check the torques)"))
            return self._record(message, status, "residual", value, t)
        message = (f"singular pose reached at t = {t + dt:.6g} s: {MEASURES[index]} measure {value:.3g} "
                   f"at x = {float(y[0]):.6g} m, y = {float(y[1]):.6g} m")
        return self._record(message, status, MEASURES[index], value, t + dt)

    @staticmethod
    def _record(message, status, variable, value, time) -> PlantRefused:
        reason, unit = REFUSALS[status]
        return PlantRefused(message, code=status, reason=reason, variable=variable, value=float(value), unit=unit,
                            time=time, names_time=True)       # every message of _record names t

    def project(self, y, iterations: int = 3):
        """Newton projection on q̄(q) = 0 and dq = C dq#, keeping q# fixed."""
        if self._fast is not None:
            return self._fast.project(y, iterations)
        mech = self.mechanism
        Qo, Qs = mech.Q_redundant, mech.Q_independent
        q, dq = y[:7].copy(), y[7:]
        for _ in range(iterations):
            st = mechanism_state(mech, q, dq)
            q -= Qo @ left_inverse_solve(st.A @ Qo, st.residual)
        C = mechanism_state(mech, q, dq).C
        return np.concatenate([q, C @ (Qs.T @ dq)])

    def _measures_of(self, y) -> list:
        """The pose measures of y (:meth:`_pose_measures`) as the C kernel's report computes them
        when there is one, so a projected state is judged with the same bits as a kernel step's."""
        if self._fast is None:
            return list(self._pose_measures(y))
        out = np.empty(fast5r.REPORT_SIZE)
        fast5r.report(self._fast.p, y, 1.0, 0.0, 0.0, out)
        return out[fast5r.REPORT_MEASURES:fast5r.REPORT_MEASURES + 3].tolist()

    @staticmethod
    def _pose_measures(y):
        """sin theta12, sin theta22 (serial) and sin(phi12 - phi22) (parallel singularity)."""
        q = y[:7].tolist()
        phi12 = q[fivebar.TH11] + q[fivebar.TH12]
        phi22 = math.pi - (q[fivebar.TH21] + q[fivebar.TH22])
        return math.sin(q[fivebar.TH12]), math.sin(q[fivebar.TH22]), math.sin(phi12 - phi22)

    # --- outputs --------------------------------------------------------------
    @property
    def q(self):
        return self.y[:7]

    @property
    def dq(self):
        return self.y[7:]

    def output_values(self) -> list:
        """:meth:`outputs`' values in its order (:data:`fmus.slave.declarations.PLANT_OUTPUTS`'),
        without the dict: after a step of the C kernel, its report's values (an FMU's doStep)."""
        last = self._last
        if last is not None and last[0] is self.y and last[2] is not None:
            values = last[2][fast5r.REPORT_OUTPUTS:fast5r.REPORT_OUTPUTS + 10]
            values.append(last[1])
            return values
        return list(self.outputs().values())

    def outputs(self) -> dict:
        """The FiveBarPlant outputs of the component contract, as Python floats."""
        last = self._last
        if last is not None and last[0] is self.y and last[2] is not None:
            o = last[2][fast5r.REPORT_OUTPUTS:]
            out = {"q1": o[0], "q2": o[1], "dq1": o[2], "dq2": o[3], "x": o[4], "y": o[5], "dx": o[6], "dy": o[7],
                   "q1_enc": o[8], "q2_enc": o[9], "residual": last[1]}
        else:
            y = self.y.tolist()
            q1, q2 = fivebar.world_angles(y[:7])
            dq1, dq2 = fivebar.world_rates(y[7:])
            out = {"q1": q1, "q2": q2, "dq1": dq1, "dq2": dq2, "x": y[0], "y": y[1], "dx": y[7], "dy": y[8],
                   "q1_enc": self._encoder(q1, self.encoder_offsets[0]),
                   "q2_enc": self._encoder(q2, self.encoder_offsets[1]), "residual": self.residual_norm()}
        return out

    def _encoder(self, q: float, offset: float) -> float:
        """The encoder's reading of the angle ``q`` with a zero error ``offset`` [rad]."""
        count = self.count
        return count * math.floor((q + offset) / count + 0.5)

    def residual_norm(self) -> float:
        """Euclidean norm of the position constraint residual q̄(q) [m] (5.18)."""
        last = self._last
        if last is not None and last[0] is self.y:   # computed by step() for this state
            return last[1]
        return self._residual_of(self.y)

    def _residual_of(self, y) -> float:
        if self._fast is not None:
            return self._fast.residual_norm(y)
        return float(np.linalg.norm(mechanism_state(self.mechanism, y[:7], y[7:]).residual))

    def kinetic_energy(self) -> float:
        """1/2 dq^T M'(q) dq, from the general model."""
        st = mechanism_state(self.mechanism, self.q, self.dq)
        return 0.5 * float(self.dq @ st.M @ self.dq)
