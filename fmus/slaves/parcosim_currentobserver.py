"""FMI slave ``CurrentObserver``: a thin adapter over :class:`motor.CurrentObserver`.

Timing and wiring (one communication step from t to t + h): feed ``v`` the
drive's output ``v`` after the drive's step over the same interval (the
voltage applied over [t, t + h]) and ``omega`` the plant's speed at t + h;
the output ``i_hat`` is the estimate for t + h, which the drive reads as its
input ``i_hat`` at the start of its next step.  A master loop
``drive.step -> observer.step -> (next) drive.step`` is thus exactly the
in-process loop ``drive.step(...); i_hat = observer.estimate(v, omega, h)``.
Outputs change only in ``doStep``: no direct feedthrough.

Sub-steps h = T / n: the estimate advances on every step (the dynamic kind integrates
over each, as the drive's electrics do) and the output ``i_hat`` is published once per
period, at the end of sub-step ``sample_phase``, held in between (:mod:`fmus.slave.sampling`).

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

from fmus.slave.base import MIN_STEP, GuardedSlave
from fmus.slave.sampling import SampledSteps, declare_sample_phase
from fmus.slave.refusals import PRESET_VALUE, motor_preset, refuse_absurd, require_finite, with_overrides
from motor import CurrentObserver as _Observer

#: Start value of the numeric motor parameters meaning "the preset's value".
MOTOR_PARAMETERS = (
    ("R", "Armature resistance [ohm], > 0"),
    ("ke", "Back-emf constant [V s/rad], > 0"),
    ("L", "Armature inductance [H], >= 0 (dynamic kind only)"),
)
OUTPUTS = ("i_hat",)


class CurrentObserver(SampledSteps, GuardedSlave):
    """Current estimate from voltage and speed, i_hat = (v - ke omega)/R (thesis 7.20)."""

    author = "parcosim"
    description = "Current observer (Coutinho 2019, 7.20): applied voltage and speed in, estimated current out"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        d = self.declare
        d("v", "input", 0.0, "Voltage applied over the step just taken (the drive's output v) [V]")
        d("omega", "input", 0.0, "Shaft speed at the end of the step [rad/s]")
        d("i_hat", "output", 0.0, "Estimated armature current at the end of the step [A]")
        d("preset", "parameter", "motor1", "Motor parameters: 'motor1' (Table 16) or 'motor2' (Table 18)")
        for name, text in MOTOR_PARAMETERS:
            d(name, "parameter", PRESET_VALUE, f"{text}; -1: the preset's value")
        d("kind", "parameter", "static",
          "'static': (v - ke omega)/R (7.20); 'dynamic': (4.162) integrated exactly over the step (needs L)")
        d("i0", "parameter", 0.0, "Estimate before the first step [A]")
        d("omega0", "parameter", 0.0,
          "Speed at the start time [rad/s]: the speed the drive holds over the first step (dynamic kind)")
        d("T", "parameter", 1e-3, "Sample time [s]: the step must divide it; i_hat is published once per period")
        declare_sample_phase(self)
        self.observer = None

    def setup(self):
        params = with_overrides(motor_preset(self), self, {name: name for name, _ in MOTOR_PARAMETERS},
                                positive=("R", "ke"))
        require_finite(T=self.T)
        refuse_absurd(i0=self.i0, omega0=self.omega0, T=self.T)
        if not self.T > 0.0:
            raise ValueError(f"parameter T = {self.T!r} s must be > 0")
        if 0.0 < self.T < MIN_STEP:
            raise ValueError(f"parameter T = {self.T!r} s must be >= {MIN_STEP:g} s")
        self.observer = _Observer(params, self.kind)
        self.observer.reset(self.i0, self.omega0)
        self.i_hat = self.observer.i_hat

    def sample(self, current_time, step_size):
        self.i_hat = self.observer.estimate(self.v, self.omega, step_size, current_time)

    def between_samples(self, current_time, step_size):
        self.observer.estimate(self.v, self.omega, step_size, current_time)
