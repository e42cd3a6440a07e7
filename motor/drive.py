"""DC motor drive: electrical model, shaft torque and current controller.

One :class:`Drive` per motor, stepped by the co-simulation master with
inputs held over each step (zero-order hold).
"""

import math

import numpy as np

import kernels
from motor import _checks, friction as lugre, kernel
from motor.current_controller import THESIS_POLES, THESIS_T, CurrentController, design_current_controller
from motor.electrics import ELECTRICAL_METHODS, electrical_step_coefficients, mean_current_coefficients

#: Names accepted for ``Drive(mode=...)``.
DRIVE_MODES = ("current", "voltage")
#: Names accepted for ``Drive(torque_output=...)``.
TORQUE_OUTPUTS = ("end", "mean")
#: Names accepted for ``Drive(friction=...)``: the regularised Coulomb + viscous friction of
#: B.2, or the LuGre model with stiction (:mod:`motor.friction`).
FRICTION_MODELS = ("tanh", "lugre")
#: Largest noise seed (a double holds integers exactly up to 2**53).
MAX_SEED = 2 ** 53


_D = kernel.indices(kernel.DRIVE)


def _design(params, T, poles):
    """:func:`design_current_controller`, its numerical failures named with the parameters."""
    try:
        return design_current_controller(params, T, poles)
    except (ValueError, RuntimeError, ArithmeticError) as exc:
        p = params
        raise ValueError(f"current controller design (app. C) failed for R = {p.R!r}, L = {p.L!r}, kt = {p.kt!r}, "
                         f"ke = {p.ke!r}, b = {p.b!r}, J_rotor = {p.J_rotor!r}, T = {T!r}: {exc}") from None


class Drive:
    """DC motor drive in current or voltage mode.

    Parameters
    ----------
    params : motor.presets.MotorParams
        Motor and driver parameters.
    mode : {"current", "voltage"}
        ``"current"``: the discrete controller K(z) (appendix C) samples
        ``i_ref`` and ``i_hat`` once per controller period T, on the step
        ``sample_phase`` of the period's steps h = T / n (0: its start), and holds
        its saturated voltage until the next sample; the electrics and the torque
        advance on every step. ``"voltage"``: the
        commanded ``v_ref``, saturated at +-v_max, is applied over the step in
        which it is given (for voltage-driven plants).
    method : {"exact", "euler", "quasi_static"}
        Integration of the electrical state over a step,
        see :func:`motor.electrics.electrical_step_coefficients`.
    T : float
        Controller sample time [s] (current mode).
    poles : sequence of 3 float
        Requested closed-loop current poles (current mode).
    torque_output : {"end", "mean"}
        Torque returned by :meth:`step`: at the step's end (B.2 with the end current), or
        averaged over the step (B.2 with the mean current,
        :func:`motor.electrics.mean_current_coefficients`), which is the torque a plant
        holding it over the step should get.
    design_params : motor.presets.MotorParams, optional
        Parameters the current controller is designed for (default ``params``): a
        controller tuned for the real motor can drive a model without some effect (e.g.
        b = 0, which would put the design's cancelled zero on z = 1).
    friction : {"tanh", "lugre"}
        Shaft friction: ``"tanh"``, mu tanh(omega/omega_eps) + b omega (B.2); ``"lugre"``,
        the LuGre model with stiction (:mod:`motor.friction`; Fc = mu, Fs = mu_s,
        ωs = omega_s, σ0 = sigma0, σ1 = sigma1, σ2 = b of ``params``), its bristle state
        solved exactly over each step with omega held.
    pwm_counts : int
        PWM resolution: the applied voltage is the nearest multiple of v_max / pwm_counts
        (0: ideal).  The controller keeps its own unquantised output.
    current_offset, current_noise : float
        Offset [A] and standard deviation [A] of a Gaussian noise added to the current the
        loop reads (``i_hat``) at each controller sample (current mode; 0: exact).
    noise_seed, noise_instance : int
        The noise of sample k is :func:`motor.drive.gaussian` (noise_seed,
        noise_instance, k): give each drive of a system its own instance.
    sample_phase : int
        Current mode: the step of each period (counted from 0 in steps h) on which the
        controller samples; must be below T / h (checked with h, :meth:`prepare_step`).

    Raises
    ------
    ValueError
        Unknown mode, method or friction, bad T or poles, current mode with L = 0, or a bad
        imperfection or LuGre parameter (named, with its value).
    """

    def __init__(self, params, mode="current", method="exact", T=THESIS_T, poles=THESIS_POLES,
                 torque_output="end", design_params=None, friction="tanh", pwm_counts=0, current_offset=0.0,
                 current_noise=0.0, noise_seed=0, noise_instance=0, sample_phase=0):
        params.validate()
        self.params = params
        self.friction = _checks.choice("friction", friction, FRICTION_MODELS)
        self.lugre = lugre.new_lugre(lugre.LuGre.of_motor(params)) if friction == "lugre" else None
        pwm_counts = _checks.count("pwm_counts", pwm_counts)
        seed = _checks.count("noise_seed", noise_seed, MAX_SEED)
        instance = _checks.count("noise_instance", noise_instance, MAX_SEED)
        self.sample_phase = _checks.count("sample_phase", sample_phase)
        offset = _checks.finite("current_offset", current_offset)
        noise = _checks.non_negative("current_noise", current_noise)
        self.torque_output = _checks.choice("torque_output", torque_output, TORQUE_OUTPUTS)
        self.mode = _checks.choice("mode", mode, DRIVE_MODES)
        self.method = _checks.choice("method", method, ELECTRICAL_METHODS)
        if self.method == "euler" and params.L == 0.0:     # its step divides by L
            raise _checks.BadValue("L", params.L, "method 'euler' needs {name} > 0, got {name} = {value!r}; "
                                   "use 'quasi_static'")
        self.T = _checks.positive("T", T)
        design = params if design_params is None else design_params
        self.controller = (CurrentController(_design(design, self.T, poles), params.v_max)
                           if mode == "current" else None)
        self._h = None
        self._coefficients = None
        self._mean = None
        # Constants and state of the step: the C struct pc_drive (kernels/src/drive.h).
        p = params
        self.buf = np.zeros(kernels.size(kernel.DRIVE))
        values = {"current_mode": 1.0 if self.mode == "current" else 0.0,
                  "mean_torque": 1.0 if self.torque_output == "mean" else 0.0,
                  "ke": p.ke, "kt": p.kt, "b": p.b, "mu": p.mu, "omega_eps": p.omega_eps, "v_max": p.v_max,
                  "T": self.T, "sample_phase": self.sample_phase, "h": math.nan,   # no step prepared (prepare_step)
                  "pwm_quantum": p.v_max / pwm_counts if pwm_counts else 0.0, "i_offset": offset,
                  "i_noise": noise, "noise_seed": seed, "noise_instance": instance}
        for name, value in values.items():
            self.buf[_D[name]] = value
        self._controller_buf = (self.controller.buf if self.controller is not None
                                else CurrentController.idle_buffer(p.v_max))
        self._bind()
        self.reset()

    def _bind(self):
        """The C calls on this drive's buffers (:class:`motor.kernel.Calls`)."""
        calls = kernel.Calls.drive(self.buf, self._controller_buf, self.lugre)
        # Bound methods only: FMU state treats them as code (an address must never be state).
        self._kernel_step, self._kernel_sample, self._kernel_torque = (calls.drive_step, calls.sample_voltage,
                                                                       calls.torque)

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k not in _BOUND}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._bind()

    i = property(lambda self: float(self.buf[_I]),
                 lambda self, value: self.buf.__setitem__(_I, value),
                 doc="Armature current [A].")
    v = property(lambda self: float(self.buf[_V]),
                 lambda self, value: self.buf.__setitem__(_V, value),
                 doc="Voltage applied over the last step [V].")

    def reset(self, i0=0.0, v0=0.0):
        """Set the armature current ``i0`` [A] and the last applied voltage ``v0`` [V] (saturated).

        In current mode the controller restarts holding ``v0`` with zero error
        (use v0 = R i0 + ke omega0 to start in electrical steady state).
        """
        v_max = self.params.v_max
        self.i = _checks.finite("i0", i0)
        self.v = min(max(_checks.finite("v0", v0), -v_max), v_max)
        self.buf[_D["phase"]] = 0.0
        self.buf[_D["sample"]] = 0.0
        if self.lugre is not None:
            self.lugre[lugre.F_Z] = 0.0
        if self.controller is not None:
            self.controller.reset(self.v)

    def start(self, omega0, i0=0.0):
        """Reset in electrical steady state: current ``i0`` at speed ``omega0``.

        The last applied voltage is v0 = R i0 + ke omega0 (4.162 with
        di/dt = 0), so the state is consistent and, in current mode, the
        controller starts holding v0 (and a static observer fed v0 and
        omega0 returns i0). Starting a spinning motor with v0 = 0 instead
        means a short-circuited, braking motor at t = 0.
        """
        omega0 = _checks.finite("omega0", omega0)
        i0 = _checks.finite("i0", i0)
        self.reset(i0, self.params.R * i0 + self.params.ke * omega0)
        if self.lugre is not None:     # sliding steadily: the bristles at their steady deflection
            self.lugre[lugre.F_Z] = lugre.steady_deflection(self.lugre, omega0)

    @property
    def z(self):
        """The LuGre bristle deflection [rad] (0 with the tanh friction); set by a plant that
        advances the bristles itself (:class:`plant.actuated.ActuatedPlant`)."""
        return 0.0 if self.lugre is None else float(self.lugre[lugre.F_Z])

    @z.setter
    def z(self, value):
        if self.lugre is None:
            raise ValueError(f"z = {value!r}: a drive with friction {self.friction!r} has no bristle deflection")
        self.lugre[lugre.F_Z] = value

    def torque(self, omega):
        """Shaft torque [N m] for the present current at speed ``omega`` (B.2, or kt i minus
        the LuGre friction (4) at the present deflection)."""
        omega = _checks.finite("omega", omega)
        return self._kernel_torque(omega)

    @property
    def substeps(self) -> int:
        """n = T / h of the steps prepared (1 in voltage mode, 0 before the first)."""
        return int(self.buf[_D["substeps"]])

    @property
    def substep(self) -> int:
        """The next step's index in its controller period (0: the period's start)."""
        return int(self.buf[_D["phase"]])

    def controller_state(self):
        """A copy of the drive's per-step state (current, voltage, controller, sub-step) for
        :meth:`restore_controller_state`: a plant that samples the voltage and then refuses
        its step (:class:`plant.actuated.ActuatedPlant`) puts the drive back as it was."""
        return self.buf.copy(), self._controller_buf.copy()

    def restore_controller_state(self, state) -> None:
        """Go back to ``state`` of :meth:`controller_state` (in place: the controller shares its array)."""
        self.buf[:], self._controller_buf[:] = state
        if not self.buf[_D["h"]] == self._h:    # a state of another step length, or of none (NaN):
            self._h = None                      # the next prepare_step computes its coefficients again

    def prepare_step(self, h):
        """Check the step length h and compute its coefficients (kept until h changes).

        Raises
        ------
        ValueError
            h not finite and > 0, or, in current mode, h not dividing T, ``sample_phase``
            not below T / h, or T / h changed within a controller period.
        """
        h = _checks.positive("h", h)
        if h != self._h:
            b = self.buf
            b[_D["substeps"]] = self._substeps(h) if self.mode == "current" else 1.0
            self._coefficients = electrical_step_coefficients(self.params.R, self.params.L, h, self.method)
            self._mean = mean_current_coefficients(self.params.R, self.params.L, h, self.method)
            b[_D["a"]], b[_D["g"]] = self._coefficients
            b[_D["w_i"]], b[_D["w_u"]] = self._mean
            b[_D["h"]] = h
            self._h = h

    def _substeps(self, h) -> int:
        """n = T / h of a step h in current mode, checked (see :meth:`prepare_step`)."""
        n = int(kernel.sampling_substeps(self.T, h))   # 0: h does not divide T (kernels/src/pc_sampling.c)
        if n == 0:
            raise ValueError(f"in current mode the step h must divide the controller period "
                             f"T={self.T!r}; got h={h!r}")
        if self.sample_phase >= n:
            raise ValueError(f"sample_phase = {self.sample_phase!r} must be below T / h = {n} "
                             f"(h = {h!r}, T = {self.T!r})")
        counted = int(self.buf[_D["substeps"]])
        if kernel.sampling_changes_period(self.substep, counted, n):
            raise ValueError(f"the step h = {h!r} s changes T / h from {counted} to {n} within a controller "
                             f"period (T = {self.T!r} s, at its sub-step {self.substep}): change it at a "
                             "period's start")
        return n

    def sample_voltage(self, i_ref, v_ref, i_hat, h):
        """The voltage applied over the next step of length h [V].

        Current mode: on the step ``sample_phase`` of a controller period T the
        controller samples ``i_ref`` and ``i_hat`` (appendix C) and its saturated output
        is held until the next sample; on the other steps the held voltage.  Voltage mode: ``v_ref`` saturated at
        +-v_max.  :meth:`step` uses it; so does a plant that integrates the armature
        current itself (:class:`plant.actuated.ActuatedPlant`), which then sets
        ``i`` and ``v`` after its step.

        Raises
        ------
        ValueError
            Naming the input, for a NaN/inf input or a bad step length.
        """
        names, values = ("i_ref", "v_ref", "i_hat", "h"), (i_ref, v_ref, i_hat, h)
        code = kernel.call(self._kernel_sample, names, values)
        if code == kernel.UNPREPARED_STEP:
            self.prepare_step(h)
            code = kernel.call(self._kernel_sample, names, values)
        if code != kernel.OK:
            raise self._refused()
        return self._kernel_sample.__self__.x[6]

    def _refused(self, h=None):
        """The :class:`kernels.Refused` of the kernel's last refusal (it changed nothing)."""
        r = self._kernel_step.__self__.refusal
        if r.code != kernel.DIVERGED:
            return kernels.refused(kernel.DRIVE_REASONS, r)
        x = self._kernel_step.__self__.x
        return kernels.refused(kernel.DRIVE_REASONS, r, i=x[7], tau=x[5], why=self._diverged_why(h))

    def step(self, i_ref, v_ref, omega, i_hat, h):
        """Advance the drive by one step with inputs held over it.

        Parameters
        ----------
        i_ref : float
            Current reference [A] (current mode).
        v_ref : float
            Commanded voltage [V] (voltage mode).
        omega : float
            Shaft speed [rad/s], held over the step.
        i_hat : float
            Observed (or measured) current at the step start [A] (current mode).
        h : float
            Step length [s]; in current mode it must divide T.

        Returns
        -------
        tau : float
            Shaft torque at the end of the step, or its mean over the step with
            ``torque_output="mean"`` [N m] (B.2).
        v : float
            Voltage applied over the step [V].
        i : float
            Armature current at the end of the step [A] (4.162).

        Raises
        ------
        ValueError
            Naming the input, for a NaN/inf input or a bad step length.
        """
        try:
            code = self._kernel_step(i_ref, v_ref, omega, i_hat, h)
        except TypeError:     # not a float: converted, or refused by name
            code = kernel.call(self._kernel_step, _STEP_INPUTS, (i_ref, v_ref, omega, i_hat, h))
        if code == kernel.UNPREPARED_STEP:
            self.prepare_step(h)
            code = kernel.call(self._kernel_step, _STEP_INPUTS, (i_ref, v_ref, omega, i_hat, h))
        if code != kernel.OK:
            raise self._refused(h)
        x = self._kernel_step.__self__.x
        return x[5], x[6], x[7]

    def _diverged_why(self, h):
        """Why the current of a step is not finite, if the method explains it."""
        a = self._coefficients[0]
        if self.method == "euler" and a < -1.0:
            L, R = self.params.L, self.params.R
            return (f": method 'euler' diverges for h = {h!r} s > 2 L/R = {2 * L / R:.3g} s (L = {L!r} H, "
                    f"R = {R!r} ohm; the current is multiplied by 1 - hR/L = {a:.3g} every step); use 'exact'")
        return ""


_I, _V = _D["i"], _D["v"]
_STEP_INPUTS = ("i_ref", "v_ref", "omega", "i_hat", "h")
#: A drive's bound C calls (rebuilt by a copy, never copied).
_BOUND = ("_kernel_step", "_kernel_sample", "_kernel_torque")


def gaussian(seed: int, instance: int, step: int) -> float:
    """A standard normal sample that depends only on (seed, instance, step), whole numbers in
    [0, 2**64): SplitMix64 (Steele, Lea, Flood 2014) hashes them, Box-Muller turns two 53-bit
    uniforms into the sample (kernels/src/drive.c).  No state: a rerun, or a restored FMU
    state, draws the same noise."""
    return kernel.gaussian(seed, instance, step)


def uniform(seed: int, instance: int, step: int) -> float:
    """A uniform sample in (0, 1] that depends only on (seed, instance, step): the first
    uniform :func:`gaussian` draws for the same three."""
    return kernel.uniform(seed, instance, step)
