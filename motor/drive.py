"""DC motor drive: electrical model, shaft torque and current controller.

One :class:`Drive` per motor, stepped by the co-simulation master with
inputs held over each step (zero-order hold).
"""

import math

import numpy as np

from motor import _checks, fastdrive, friction as lugre
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

# Relative tolerance used to decide that h divides T.
_PHASE_TOL = 1e-6


def _floats(*values):
    """The values as floats (the kernels' one signature); a value that is not a number
    becomes NaN, which the kernel refuses and the caller names with its original value."""
    try:
        return tuple(float(v) for v in values)
    except (TypeError, ValueError):
        return tuple(v if isinstance(v, float) else math.nan for v in values)


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
        ``i_ref`` and ``i_hat`` at the start of each controller period T and
        holds its saturated voltage over the period. ``"voltage"``: the
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
        The noise of sample k is :func:`motor.fastdrive.gaussian` (noise_seed,
        noise_instance, k): give each drive of a system its own instance.

    Raises
    ------
    ValueError
        Unknown mode, method or friction, bad T or poles, current mode with L = 0, or a bad
        imperfection or LuGre parameter (named, with its value).
    """

    def __init__(self, params, mode="current", method="exact", T=THESIS_T, poles=THESIS_POLES,
                 torque_output="end", design_params=None, friction="tanh", pwm_counts=0, current_offset=0.0,
                 current_noise=0.0, noise_seed=0, noise_instance=0):
        params.validate()
        self.params = params
        self.friction = _checks.choice("friction", friction, FRICTION_MODELS)
        self.lugre = lugre.new_lugre(lugre.LuGre.of_motor(params)) if friction == "lugre" else None
        pwm_counts = _checks.count("pwm_counts", pwm_counts)
        seed = _checks.count("noise_seed", noise_seed, MAX_SEED)
        instance = _checks.count("noise_instance", noise_instance, MAX_SEED)
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
        # Constants and state of the per-step arithmetic (motor.fastdrive's layout).
        p = params
        self.buf = np.zeros(fastdrive.DRIVE_SIZE)
        self.buf[fastdrive.D_CURRENT_MODE] = 1.0 if self.mode == "current" else 0.0
        self.buf[fastdrive.D_MEAN_TORQUE] = 1.0 if self.torque_output == "mean" else 0.0
        self.buf[fastdrive.D_KE:fastdrive.D_T + 1] = (p.ke, p.kt, p.b, p.mu, p.omega_eps, p.v_max, self.T)
        self.buf[fastdrive.D_H] = math.nan     # no step prepared (prepare_step)
        self.buf[fastdrive.D_PWM_QUANTUM] = p.v_max / pwm_counts if pwm_counts else 0.0
        self.buf[fastdrive.D_I_OFFSET:fastdrive.D_NOISE_INSTANCE + 1] = (offset, noise, seed, instance)
        self._controller_buf = (self.controller.buf if self.controller is not None
                                else fastdrive.new_controller(0.0, 0.0, 0.0, 0.0, p.v_max))
        self.reset()
        # Compile the step kernels (or load numba's cache) now, on copies: the construction
        # (an FMU's initialisation), not the first step, pays for it.
        fastdrive.drive_step(self.buf.copy(), self._controller_buf.copy(), 0.0, 0.0, 0.0, 0.0, math.nan)
        fastdrive.sample_voltage(self.buf.copy(), self._controller_buf.copy(), 0.0, 0.0, 0.0, math.nan)
        if self.lugre is not None:
            lugre.friction_peek(self.lugre, 0.0, 1.0)
            fastdrive.drive_step_friction(self.buf.copy(), self._controller_buf.copy(), 0.0, 0.0, 0.0, 0.0,
                                          math.nan, 0.0, 0.0)

    i = property(lambda self: float(self.buf[fastdrive.D_I]),
                 lambda self, value: self.buf.__setitem__(fastdrive.D_I, value),
                 doc="Armature current [A].")
    v = property(lambda self: float(self.buf[fastdrive.D_V]),
                 lambda self, value: self.buf.__setitem__(fastdrive.D_V, value),
                 doc="Voltage applied over the last step [V].")

    def reset(self, i0=0.0, v0=0.0):
        """Set the armature current ``i0`` [A] and the last applied voltage ``v0`` [V] (saturated).

        In current mode the controller restarts holding ``v0`` with zero error
        (use v0 = R i0 + ke omega0 to start in electrical steady state).
        """
        v_max = self.params.v_max
        self.i = _checks.finite("i0", i0)
        self.v = min(max(_checks.finite("v0", v0), -v_max), v_max)
        self.buf[fastdrive.D_PHASE] = 0.0
        self.buf[fastdrive.D_SAMPLE] = 0.0
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
        if self.lugre is not None:
            return self.params.kt * self.i - lugre.friction_force(self.lugre, self.lugre[lugre.F_Z], omega)
        return fastdrive.shaft_torque(self.buf, self.i, omega)

    def controller_state(self):
        """A copy of the drive's per-step state (current, voltage, controller, phase) for
        :meth:`restore_controller_state`: a plant that samples the voltage and then refuses
        its step (:class:`plant.actuated.ActuatedPlant`) puts the drive back as it was."""
        return self.buf.copy(), self._controller_buf.copy()

    def restore_controller_state(self, state) -> None:
        """Go back to ``state`` of :meth:`controller_state` (in place: the controller shares its array)."""
        self.buf[:], self._controller_buf[:] = state

    def prepare_step(self, h):
        """Check the step length h and compute its coefficients (kept until h changes).

        Raises
        ------
        ValueError
            h not finite and > 0, or, in current mode, h not dividing T.
        """
        h = _checks.positive("h", h)
        if h != self._h:
            if self.mode == "current":
                n = self.T / h
                if n < 1.0 - _PHASE_TOL or abs(n - round(n)) > _PHASE_TOL * n:
                    raise ValueError(f"in current mode the step h must divide the controller period "
                                     f"T={self.T!r}; got h={h!r}")
            self._coefficients = electrical_step_coefficients(self.params.R, self.params.L, h, self.method)
            self._mean = mean_current_coefficients(self.params.R, self.params.L, h, self.method)
            b = self.buf
            b[fastdrive.D_A], b[fastdrive.D_G] = self._coefficients
            b[fastdrive.D_WI], b[fastdrive.D_WU] = self._mean
            b[fastdrive.D_PHASE_STEP] = h / self.T
            b[fastdrive.D_H] = h
            self._h = h

    def sample_voltage(self, i_ref, v_ref, i_hat, h):
        """The voltage applied over the next step of length h [V].

        Current mode: at the start of a controller period T the controller samples
        ``i_ref`` and ``i_hat`` (appendix C) and its saturated output is held over the
        period; within a period the held voltage.  Voltage mode: ``v_ref`` saturated at
        +-v_max.  :meth:`step` uses it; so does a plant that integrates the armature
        current itself (:class:`plant.actuated.ActuatedPlant`), which then sets
        ``i`` and ``v`` after its step.

        Raises
        ------
        ValueError
            Naming the input, for a NaN/inf input or a bad step length.
        """
        args = _floats(i_ref, v_ref, i_hat, h)
        status, v = fastdrive.sample_voltage(self.buf, self._controller_buf, *args)
        if status == fastdrive.UNPREPARED_STEP:
            self.prepare_step(h)
            status, v = fastdrive.sample_voltage(self.buf, self._controller_buf, *args)
        if status != fastdrive.OK:
            self._refuse(status, i_ref, v_ref, i_hat)
        return v

    def _refuse(self, status, i_ref, v_ref, i_hat, omega=0.0):
        """Raise the message of a refusal of :mod:`motor.fastdrive` (nothing was changed)."""
        for name, value in (("omega", omega), ("i_ref", i_ref), ("v_ref", v_ref), ("i_hat", i_hat)):
            _checks.finite(name, value)
        raise RuntimeError(f"motor.fastdrive refused a step with status {status} that the Python checks accept")

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
        args = _floats(i_ref, v_ref, omega, i_hat, h)
        status, tau, v, i = self._step(args)
        if status == fastdrive.UNPREPARED_STEP:
            self.prepare_step(h)
            status, tau, v, i = self._step(args)
        if status == fastdrive.DIVERGED:
            raise ValueError(self._diverged(i, tau, h))
        if status != fastdrive.OK:
            self._refuse(status, i_ref, v_ref, i_hat, omega)
        return tau, v, i

    def _step(self, args):
        """The kernel's (status, tau, v, i); with LuGre friction its bristles advance too
        (kept only when the drive's step is)."""
        if self.lugre is None:
            return fastdrive.drive_step(self.buf, self._controller_buf, *args)
        omega, h = args[2], args[4]
        _, z, f_end, f_mean = lugre.friction_peek(self.lugre, omega, h if h > 0.0 else 1.0)
        result = fastdrive.drive_step_friction(self.buf, self._controller_buf, *args, f_end, f_mean)
        if result[0] == fastdrive.OK:
            lugre.friction_commit(self.lugre, z)
        return result

    def _diverged(self, i, tau, h):
        """Why the current or torque of a step is not finite."""
        text = f"armature current i = {i!r} A, shaft torque tau = {tau!r} N m after this step are not finite"
        a = self._coefficients[0]
        if self.method == "euler" and a < -1.0:
            L, R = self.params.L, self.params.R
            text += (f": method 'euler' diverges for h = {h!r} s > 2 L/R = {2 * L / R:.3g} s (L = {L!r} H, "
                     f"R = {R!r} ohm; the current is multiplied by 1 - hR/L = {a:.3g} every step); use 'exact'")
        return text
