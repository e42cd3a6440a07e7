"""FMI slave ``DCMotorDrive``: a thin adapter over :class:`motor.Drive`.

Timing (one communication step from t to t + h, inputs held over it):
``v`` is the voltage applied over [t, t + h] (in current mode the controller
samples ``i_ref`` and ``i_hat`` at t and holds its voltage), ``i`` and
``tau`` are the current and shaft torque at t + h (with ``torque_output = "mean"``,
``tau`` is the shaft torque averaged over [t, t + h]).  Outputs change only in
``doStep``: no direct feedthrough.

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

import math

from fmus.guarded import PRESET_VALUE, GuardedSlave, refuse_absurd, with_overrides
from motor import Drive, get_motor_preset

#: Start value of the numeric motor parameters meaning "the preset's value".
#: Motor parameters settable one by one (MotorParams field -> FMU variable, description).
MOTOR_PARAMETERS = (
    ("R", "R", "Armature resistance [ohm], > 0"),
    ("L", "L", "Armature inductance [H], >= 0 (0: quasi-static, voltage mode only)"),
    ("kt", "kt", "Torque constant [N m/A], > 0"),
    ("ke", "ke", "Back-emf constant [V s/rad], > 0"),
    ("b", "b", "Viscous friction [N m s/rad], >= 0"),
    ("mu", "mu", "Coulomb friction torque [N m], >= 0"),
    ("v_max", "v_max", "Supply voltage: the driver saturates at +-v_max [V], > 0"),
    ("omega_eps", "omega_eps", "Width of the regularised sign mu*tanh(omega/omega_eps) [rad/s], > 0"),
    ("J_rotor", "J_design", "Rotor inertia assumed by the current-controller design G_I(s) (B.10) only "
                            "[kg m2], > 0; the plant integrates the real rotor inertia"),
)
OUTPUTS = ("tau", "v", "i")


class DCMotorDrive(GuardedSlave):
    """DC motor with its 1 ms discrete current controller (thesis 4.162, B.2, app. C, 7.2.10)."""

    author = "parcosim"
    description = ("DC motor drive (Coutinho 2019, 4.162, B.2, app. C): current reference or voltage in, "
                   "shaft torque out")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        d = self.declare
        d("i_ref", "input", 0.0, "Current reference, sampled at the step start (current mode) [A]")
        d("v_ref", "input", 0.0, "Commanded voltage, applied over the step, saturated at +-v_max (voltage mode) [V]")
        d("omega", "input", 0.0, "Shaft speed, held over the step [rad/s]")
        d("i_hat", "input", 0.0, "Observed (or measured) current at the step start (current mode) [A]")
        d("tau", "output", 0.0, "Shaft torque kt i - b omega - mu sign(omega) at the step end [N m]")
        d("v", "output", 0.0, "Voltage applied over the step just taken [V]")
        d("i", "output", 0.0, "Armature current at the step end [A]")
        d("preset", "parameter", "motor1", "Motor parameters: 'motor1' (Table 16) or 'motor2' (Table 18)")
        for _, var, text in MOTOR_PARAMETERS:
            d(var, "parameter", PRESET_VALUE, f"{text}; -1: the preset's value")
        d("mode", "parameter", "current", "'current' (controller K(z) on i_ref, i_hat) or 'voltage' (v_ref applied)")
        d("method", "parameter", "exact",
          "Electrical integration over a step: 'exact' (analytic), 'euler' (explicit) or 'quasi_static' (L = 0)")
        d("b_design", "parameter", PRESET_VALUE,
          "Viscous friction assumed by the current-controller design only [N m s/rad], > 0; -1: b")
        d("torque_output", "parameter", "end",
          "'end': tau is the shaft torque at the step's end; 'mean': its average over the step "
          "(what a plant holding tau over the step should get)")
        d("T", "parameter", 1e-3, "Current-controller sample time [s]; in current mode the step must divide it")
        d("omega0", "parameter", 0.0, "Start in electrical steady state at this speed [rad/s]")
        d("i0", "parameter", 0.0, "Start in electrical steady state with this current [A]")
        self.drive = None

    def setup(self):
        params = with_overrides(get_motor_preset(self.preset), self, [(field, var) for field, var, _ in MOTOR_PARAMETERS])
        refuse_absurd(T=self.T, omega0=self.omega0, i0=self.i0)
        design = None
        if self.b_design != PRESET_VALUE:
            refuse_absurd(b_design=self.b_design)
            if not (math.isfinite(self.b_design) and self.b_design > 0.0):
                raise ValueError(f"parameter b_design = {self.b_design!r} must be > 0 (or -1: the value of b)")
            design = params.with_(b=self.b_design)
        self.drive = Drive(params, mode=self.mode, method=self.method, T=self.T, torque_output=self.torque_output,
                           design_params=design)
        self.drive.start(self.omega0, self.i0)
        self.tau = self.drive.torque(self.omega0)
        self.v = self.drive.v
        self.i = self.drive.i

    def step(self, current_time, step_size):
        self.tau, self.v, self.i = self.drive.step(self.i_ref, self.v_ref, self.omega, self.i_hat, step_size)
