"""FMI slave ``BalanceController``: the wheeled pendulum's discrete balance controller.

A thin adapter over :class:`controller.balance.BalanceController` (observer + LQR designed
with python-control at initialisation).  The sample's ``doStep(t, h)`` reads the encoders
and the gyro at t and outputs the motor voltages held over [t, t + T], saturated at
``v_battery``; steps h = T / n sample once per period, on sub-step ``sample_phase``, and
hold in between (:mod:`fmus.slave.sampling`); outputs change only in ``doStep``: no direct feedthrough.

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

from controller.balance import ROUTES, BalanceController as _Controller
from controller.balance import BalanceSettings, design_balance, get_route
from controller.fastbalance import INPUTS, OUTPUTS
from fmus.slave.base import MIN_STEP, GuardedSlave
from fmus.slave.sampling import SampledSteps, declare_sample_phase
from fmus.slave.refusals import refuse_absurd, refuse_absurd_inputs, require_finite

ESTIMATES = OUTPUTS[6:]


class BalanceController(SampledSteps, GuardedSlave):
    """Observer + discrete LQR on pitch, wheel position and yaw (seed 000's robot)."""

    author = "parcosim"
    description = ("Balance controller of the wheeled pendulum (seed 000): encoders and gyro in, "
                   "motor voltages out; Kalman observer + discrete LQR")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        defaults = BalanceSettings()
        d = self.declare
        d("enc_l", "input", 0.0, "Left wheel encoder, theta_l - psi [rad]")
        d("enc_r", "input", 0.0, "Right wheel encoder, theta_r - psi [rad]")
        d("gyro", "input", 0.0, "Pitch-rate gyro [rad/s]")
        d("v_l", "output", 0.0, "Left motor voltage, held over the sample [V]")
        d("v_r", "output", 0.0, "Right motor voltage, held over the sample [V]")
        d("tau_l", "output", 0.0, "Torque an ideal drive would give for v_l, (K_t/R_m) v_l [N m]")
        d("tau_r", "output", 0.0, "Torque an ideal drive would give for v_r, (K_t/R_m) v_r [N m]")
        d("x_d", "output", 0.0, "Reference axle position x at the sample [m]")
        d("y_d", "output", 0.0, "Reference axle position y at the sample [m]")
        for name in ESTIMATES:
            d(name, "output", 0.0, f"Observer's prediction of {name[:-4]} for the next sample")
        d("T", "parameter", defaults.T, "Sample time; doStep sizes must divide it [s]")
        declare_sample_phase(self)
        d("v_battery", "parameter", defaults.v_battery, "Voltage saturation [V] (an assumption: seed 000 gives none)")
        d("electrics", "parameter", defaults.electrics, "Design model of the drives: 'quasi_static' (seed 000 (22)) "
          "or 'ideal' (torque sources, no back-EMF)")
        d("friction", "parameter", defaults.friction, "The design models the motors' friction f_m")
        d("yaw", "parameter", defaults.yaw, "Control the yaw (false: the heading is locked)")
        d("encoder_counts", "parameter", defaults.encoder_counts, "Encoder counts per revolution (observer noise)")
        d("route", "parameter", "hold", "Reference: 'hold' (stay at the origin) or 'forward_turn' "
          "(1 m forward along +x over 0.5-5.5 s, then 90 deg left in place over 6-8 s)")
        self.controller = None

    def setup(self):
        require_finite(T=self.T, v_battery=self.v_battery)
        refuse_absurd(T=self.T, v_battery=self.v_battery)
        if not self.T >= MIN_STEP:
            raise ValueError(f"parameter T = {self.T!r} s must be >= {MIN_STEP:g} s")
        if self.route not in ROUTES:
            raise ValueError(f"parameter route = {self.route!r}; valid: {', '.join(ROUTES)}")
        settings = BalanceSettings(T=self.T, v_battery=self.v_battery, electrics=self.electrics,
                                   friction=bool(self.friction), yaw=bool(self.yaw),
                                   encoder_counts=self.encoder_counts)
        self.controller = _Controller(design_balance(settings), get_route(self.route))

    def sample(self, current_time, step_size):
        c = self.controller
        refuse_absurd_inputs(current_time, enc_l=self.enc_l, enc_r=self.enc_r, gyro=self.gyro)
        c.sample(current_time, self.enc_l, self.enc_r, self.gyro)
        for name, value in zip(OUTPUTS, c.io[len(INPUTS):].tolist()):
            setattr(self, name, value)
