"""FMI slave ``WheeledPendulum``: a thin adapter over :class:`plant.wheeled.WheeledPendulum`.

The robot falling over (|psi| beyond 90 degrees or the body touching the floor) is an outcome,
not a crash: ``fallen`` becomes true, the other outputs keep the last standing state, and
the step returns fmi2Discard with a message naming psi and the time.

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

from dataclasses import fields

from fmus.slave import budget
from fmus.slave.base import GuardedSlave
from fmus.slave.refusals import refuse_absurd, refuse_absurd_inputs, refuse_tiny, require_finite

#: (output, description) of the pendulum (docs/contract.md).
OUTPUTS = (
    ("theta", "Mean wheel angle from the vertical, (theta_l + theta_r)/2 [rad]"),
    ("psi", "Body pitch, 0 upright, + leaning toward the heading [rad]"),
    ("phi", "Yaw, CCW from +x [rad]"),
    ("dtheta", "theta' [rad/s]"),
    ("dpsi", "psi' [rad/s]"),
    ("dphi", "phi' [rad/s]"),
    ("x", "Axle midpoint x [m]"),
    ("y", "Axle midpoint y [m]"),
    ("omega_l", "Left motor speed relative to the body, theta_l' - psi' [rad/s]"),
    ("omega_r", "Right motor speed relative to the body, theta_r' - psi' [rad/s]"),
    ("enc_l", "Left wheel encoder: theta_l - psi quantised to encoder_counts per revolution [rad]"),
    ("enc_r", "Right wheel encoder: theta_r - psi quantised to encoder_counts per revolution [rad]"),
    ("gyro", "Pitch-rate gyro: psi' [rad/s]"),
    ("energy", "Kinetic plus potential energy [J]"),
)
#: The initial-state parameters, with the state entry each sets.
INITIAL = (("theta0", "theta"), ("psi0", "psi"), ("phi0", "phi"), ("dtheta0", "dtheta"), ("dpsi0", "dpsi"),
           ("dphi0", "dphi"), ("x0", "x"), ("y0", "y"))
_TEXT = {"g": "Gravity [m/s2]", "m": "Wheel mass [kg]", "R": "Wheel radius [m]",
         "J_w": "Wheel spin inertia [kg m2] (seed: m R^2/2)", "M": "Body mass [kg]", "W": "Body width [m]",
         "D": "Body depth [m]", "H": "Body height [m]", "L": "Axle to body centre of mass [m] (seed: H/2)",
         "J_psi": "Body pitch inertia [kg m2] (seed: M L^2/3)",
         "J_phi": "Body yaw inertia [kg m2] (seed: M (W^2 + D^2)/12)"}


class WheeledPendulum(GuardedSlave):
    """Two-wheeled inverted pendulum of seed 000: wheel torques in, motion and sensors out."""

    author = "parcosim"
    description = ("Two-wheeled inverted pendulum (seed 000), rolling constraints by Lagrange-d'Alembert: "
                   "wheel torques in, motion, encoders and gyro out")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        from plant.wheeled import SEED, SUBSTEPS

        d = self.declare
        d("tau_l", "input", 0.0, "Motor torque on the left wheel, + drives it forward; reaction on the body [N m]")
        d("tau_r", "input", 0.0, "Motor torque on the right wheel, + drives it forward; reaction on the body [N m]")
        d("tau_d", "input", 0.0, "Disturbance torque on the body about the axle, + toward the heading [N m]")
        for name, text in OUTPUTS:
            d(name, "output", 0.0, text)
        d("fallen", "output", False, "The robot fell over (|psi| beyond 90 deg or the body on the floor)")
        for f in fields(SEED):
            d(f.name, "parameter", float(getattr(SEED, f.name)), _TEXT[f.name])
        for name, entry in INITIAL:
            d(name, "parameter", 0.0, f"Initial {entry}")
        d("model", "parameter", "exact", "'exact' (Lagrange-d'Alembert) or 'seed' (seed 000's equations, "
          "typos corrected, without the two nonholonomic terms)")
        d("yaw", "parameter", True, "Model the yaw (false: heading locked, for straight-line scenes)")
        d("substeps", "parameter", SUBSTEPS, "RK4 steps per communication step")
        d("encoder_counts", "parameter", 4096, "Wheel encoder counts per revolution (quadrature)")
        d("push_torque", "parameter", 0.0, "A push: this torque on the body [N m], added to tau_d ...")
        d("push_start", "parameter", 0.0, "... over the steps that start in [push_start, push_start + push_duration) [s]")
        d("push_duration", "parameter", 0.0, "Duration of the push [s]")
        self.sim = None

    def setup(self):
        from motor._checks import BadValue
        from plant.wheeled import POSITIVE, SEED, WheeledPendulum as Simulator

        values = {f.name: float(getattr(self, f.name)) for f in fields(SEED)}
        initial = {entry: float(getattr(self, name)) for name, entry in INITIAL}
        require_finite(**{f"parameter {k}": v for k, v in {**values, **{n: getattr(self, n) for n, _ in INITIAL}}.items()})
        push = {name: float(getattr(self, name)) for name in ("push_torque", "push_start", "push_duration")}
        require_finite(**{f"parameter {k}": v for k, v in push.items()})
        refuse_absurd(**values, **push, **{name: float(getattr(self, name)) for name, _ in INITIAL})
        if self.push_duration < 0.0:
            raise ValueError(f"parameter push_duration = {self.push_duration!r} s must be >= 0")
        refuse_tiny(**{name: values[name] for name in POSITIVE})     # the model divides by them
        params = SEED.with_(**values)
        try:
            self.sim = Simulator(params, model=self.model, yaw=bool(self.yaw), initial=initial,
                                 substeps=self.substeps, encoder_counts=self.encoder_counts)
        except BadValue as exc:     # an initial state entry, named as the slave's parameter
            raise exc.renamed({entry: name for name, entry in INITIAL}) from None
        self.publish()

    def known_step_work(self) -> float:
        """The CPU [s] a step is charged: 4 evaluations a substep (:mod:`fmus.slave.budget`)."""
        return 4 * self.sim.substeps * budget.WHEELED_RK4_EVALUATION

    def publish(self):
        for name, value in self.sim.outputs().items():
            setattr(self, name, value)

    def step(self, current_time, step_size):
        from plant.wheeled import FallenError

        self.sim.time = current_time
        refuse_absurd_inputs(current_time, tau_l=self.tau_l, tau_r=self.tau_r, tau_d=self.tau_d)
        tau_d = self.tau_d
        # the push acts over the steps that start inside its window (1e-9 s: rounding of t)
        if self.push_start - 1e-9 <= current_time < self.push_start + self.push_duration - 1e-9:
            tau_d += self.push_torque
        sim = self.sim

        def run(_):
            sim.step(self.tau_l, self.tau_r, step_size, tau_d)
            return 4 * sim.substeps

        try:
            if budget.active() is None:     # alone: any substeps allowed fit a call
                run(None)
            else:
                budget.bounded_integration(run, budget.WHEELED_RK4_EVALUATION, 4 * sim.substeps,
                                           "right-hand-side evaluations (RK4)", current_time, step_size,
                                           "take shorter steps or use fewer substeps")
        except FallenError:
            self.fallen = True
            raise
        self.publish()
