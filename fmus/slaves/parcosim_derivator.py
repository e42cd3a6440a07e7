"""FMI slave ``Derivator``: velocity and acceleration estimates of q1, q2 (thesis 7.2.3).

Each ``doStep(t, h)`` takes the inputs ``q1``, ``q2`` as the newest sample and outputs the
estimates at that sample (:class:`controller.derivators.Derivator`: backward difference,
2nd-order Bessel low-pass for velocity, 8th-order for acceleration, discretised at
``T``).  Steps h = T / n sample once per period, on sub-step ``sample_phase``, and hold the
estimates in between (:mod:`fmus.slave.sampling`).  Wiring: feed the plant's (encoder) angles at t and
read the estimates for t after this step, before the controller's step at t.  Outputs
change only in ``doStep``: no direct feedthrough.

Start: with ``start_from_input`` (default) the filters are put at rest at the angles of the
first ``doStep``'s inputs, so the first estimates are 0 (the thesis' bench starts at rest);
otherwise at rest at the parameters ``q1_0``, ``q2_0``.

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

import math

import numpy as np

from controller.derivators import DEFAULT_FC_ACC, DEFAULT_FC_VEL, SAMPLE_TIME
from controller.derivators import Derivator as _Derivator
from fmus.slave import designs
from fmus.slave.base import MIN_STEP, GuardedSlave
from fmus.slave.sampling import SampledSteps, declare_sample_phase
from fmus.slave.refusals import ABSURD, refuse_absurd, require_finite
from kernels import timed

OUTPUTS = ("dq1", "dq2", "ddq1", "ddq2")
#: Lowest fc T of a filter: below (fc T ~ 1e-9) the discretised Bessel filters are singular.
MIN_FC_T = 1e-6


class Derivator(SampledSteps, GuardedSlave):
    """Numerical differentiator of the two actuated angles (7.2.3)."""

    #: 2 since the derivator's buffer holds its sections (layout 1: its dense step matrix).
    STATE_LAYOUT = 2

    author = "parcosim"
    description = "Derivator (Coutinho 2019, 7.2.3): angles in, Bessel-filtered velocity and acceleration out"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        designs.load(self.resources)   # what its build computed ahead (fmus/slave/designs.py)
        d = self.declare
        d("q1", "input", 0.0, "Chain 1 actuated angle sample [rad]")
        d("q2", "input", 0.0, "Chain 2 actuated angle sample [rad]")
        d("dq1", "output", 0.0, "Velocity estimate of q1 [rad/s]")
        d("dq2", "output", 0.0, "Velocity estimate of q2 [rad/s]")
        d("ddq1", "output", 0.0, "Acceleration estimate of q1 [rad/s2]")
        d("ddq2", "output", 0.0, "Acceleration estimate of q2 [rad/s2]")
        d("fc_vel", "parameter", DEFAULT_FC_VEL, "-3 dB frequency of the 2nd-order Bessel velocity low-pass [Hz]")
        d("fc_acc", "parameter", DEFAULT_FC_ACC, "-3 dB frequency of the 8th-order Bessel acceleration low-pass [Hz]")
        d("T", "parameter", SAMPLE_TIME, "Sample time the filters are discretised at; doStep sizes must divide it [s]")
        declare_sample_phase(self)
        d("start_from_input", "parameter", True, "Start at rest at the first step's input angles (else at q1_0, q2_0)")
        d("q1_0", "parameter", 0.0, "Start angle of q1 when start_from_input is false [rad]")
        d("q2_0", "parameter", 0.0, "Start angle of q2 when start_from_input is false [rad]")
        self.derivator = None

    def setup(self):
        require_finite(fc_vel=self.fc_vel, fc_acc=self.fc_acc, T=self.T, q1_0=self.q1_0, q2_0=self.q2_0)
        refuse_absurd(fc_vel=self.fc_vel, fc_acc=self.fc_acc, T=self.T, q1_0=self.q1_0, q2_0=self.q2_0)
        for name in ("fc_vel", "fc_acc", "T"):
            if getattr(self, name) <= 0.0:
                raise ValueError(f"parameter {name} = {getattr(self, name)!r} must be > 0")
        if self.T < MIN_STEP:
            raise ValueError(f"parameter T = {self.T!r} s is below the shortest step {MIN_STEP:g} s")
        nyquist = 0.5 / self.T
        lowest = MIN_FC_T / self.T
        for name in ("fc_vel", "fc_acc"):
            if getattr(self, name) >= nyquist:
                raise ValueError(f"parameter {name} = {getattr(self, name)!r} Hz must be below 1/(2T) = {nyquist:g} Hz")
            if getattr(self, name) < lowest:
                raise ValueError(f"parameter {name} = {getattr(self, name)!r} Hz is below {MIN_FC_T:g}/T = "
                                 f"{lowest:g} Hz: the filter discretised at T = {self.T!r} s would be singular")
        try:
            self.derivator = _Derivator(self.fc_vel, self.fc_acc, self.T)
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            raise ValueError(f"parameters fc_vel = {self.fc_vel!r} Hz, fc_acc = {self.fc_acc!r} Hz, T = {self.T!r} s: "
                             f"the filter design failed ({exc})") from None
        if self.start_from_input:
            self.derivator.start_at_first_sample(2)
        else:
            self.derivator.reset([self.q1_0, self.q2_0])

    def sample(self, current_time, step_size):
        q1, q2 = self.q1, self.q2
        if not (abs(q1) <= ABSURD and abs(q2) <= ABSURD):   # NaN fails too: named below
            self._refuse_inputs(current_time)
        estimates = self.derivator.step_values((q1, q2), ABSURD)
        dq1, dq2, ddq1, ddq2 = estimates
        # One check of the sum in the usual case: a NaN or an infinity makes it not finite (so do
        # finite values whose sum overflows: they are checked one by one then).
        if not math.isfinite(dq1 + dq2 + ddq1 + ddq2) and not all(map(math.isfinite, estimates)):
            raise timed(ValueError(f"the estimates (dq1, dq2, ddq1, ddq2) = {tuple(estimates)!r} at t = "
                                   f"{current_time:.6g} s are not finite (inputs q1 = {self.q1!r}, q2 = {self.q2!r} rad)"))
        self.dq1, self.dq2, self.ddq1, self.ddq2 = dq1, dq2, ddq1, ddq2

    def _refuse_inputs(self, current_time):
        """Raise ValueError naming the first input that is not finite or is absurd."""
        for name in ("q1", "q2"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise timed(ValueError(f"input {name} = {value!r} at t = {current_time:.6g} s is not finite"))
            if abs(value) > ABSURD:
                raise timed(ValueError(f"input {name} = {value!r} rad at t = {current_time:.6g} s is absurd: "
                                       f"|{name}| must be <= {ABSURD:g} rad"))
