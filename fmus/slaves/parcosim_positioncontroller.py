"""FMI slave ``PositionController``: the unified law (thesis 7.21-7.22), eight strategies, and
seed 001's sliding-mode law (SMCq, SMCx).  ``gravity_x``, ``gravity_y``, ``counter_mass1``,
``counter_mass2`` describe the plant its model (Ĥ, ĥ of 5.74-5.77) is built for.

Timing: ``doStep(t, h)`` reads the measurements and references set before it (the samples
at t), computes the torques and current references and holds them as outputs; the master
applies them to the drives/plant over [t, t + h].  Outputs change only in ``doStep``: no
direct feedthrough.  Steps h = T / n sample once per period, on sub-step ``sample_phase``,
and hold in between (:mod:`fmus.slave.sampling`); T is the integration step of the sliding term.  ``delay_steps`` = n > 0
models a computation delay (docs/twin.md: on the bench of 7.2.1 a Raspberry Pi 2 reads the
encoders at a sample and computes the law; the thesis does not say when the commands reach
the driver, the twin assumes at the next sample): the outputs ``tau1``,
``tau2``, ``i_ref1``, ``i_ref2`` of ``doStep(t)`` are those computed n samples earlier (zero
before), ``e1``, ``e2`` stay the present errors.  ``delay_compensation`` = a and
``velocity_delay_compensation`` = b > 0: the angles and rates are a and b periods old when the
commands take effect (a per-component package at 1 ms in a Jacobi master: 2 and 3); the law
acts on the joint state its model predicts for then and on the reference a periods on
(``kernels/src/law.h``), and ``e1``, ``e2`` are the errors of that prediction.

Numeric parameters ``lam``, ``m_star``, ``phi``, ``k1``, ``k2``, ``kt1``, ``kt2`` start at -1,
meaning "the strategy preset's value" (Tables 6-8; ``trajectory`` picks Table 6 or 7 for
joint-space strategies) or the motor presets' kt.  ``gamma1``, ``gamma2`` > 0 turn on the
adaptive gain (6.66).  The tabulated model's table travels in the FMU's resources, built with
the FMU for its parameters then (:mod:`fmus.slave.designs`); other parameters (the grid ``grid_step``,
``x_min`` ... ``y_max``, the plant's, ``model_error``) give another table, loaded from the user's
cache (``controller.model.cache_dir``) or built at initialisation, which the log says.

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from pythonfmu.enums import Fmi2Status

from controller.law import MAX_PREDICT, delay
from controller.model import DEFAULT_EXTENT, DEFAULT_GRID_STEP
from controller.position import PositionController as _Controller
from controller.strategies import get_strategy
from fmus.slave import designs
from fmus.slave.base import MIN_STEP, GuardedSlave
from fmus.slave.sampling import SampledSteps, declare_sample_phase
from fmus.slave.refusals import PRESET_VALUE, refuse_absurd, refuse_tiny, require_finite
from fmus.slave.declarations import declare_counter_masses, with_counter_masses
from plant import get_preset

#: Start value meaning "the preset's value".
INPUTS = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")
OUTPUTS = ("tau1", "tau2", "i_ref1", "i_ref2")
NUMERIC_PARAMETERS = ("lam", "m_star", "phi", "k1", "k2", "gamma1", "gamma2", "model_error", "kt1", "kt2",
                      "grid_step", "x_min", "x_max", "y_min", "y_max", "T", "gravity_x", "gravity_y")
#: Most samples of computation delay ``delay_steps`` (the bench's is one: docs/twin.md).
MAX_DELAY_STEPS = 100
#: Most points a tabulated model's grid may have (the default 5 mm table has 2303, built in
#: about 0.2 s; a point costs about 80 µs): building more would take fmi2ExitInitializationMode
#: over the 10 s any call may take (docs/extremes.md).
MAX_TABLE_POINTS = 6e4


class PositionController(SampledSteps, GuardedSlave):
    """Discrete position controller of the 5R (Coutinho 2019, 7.2.6, 7.21-7.22)."""

    author = "parcosim"
    description = "Position controller (Coutinho 2019, 7.21-7.22): PD/TC +- sliding modes, joint or task space"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        designs.load(self.resources)   # what its build computed ahead (fmus/slave/designs.py)
        d = self.declare
        for name, text in (("q1", "Measured q1 [rad]"), ("q2", "Measured q2 [rad]"),
                           ("dq1", "Measured dq1 [rad/s]"), ("dq2", "Measured dq2 [rad/s]"),
                           ("ddq1", "Measured ddq1 [rad/s2]"), ("ddq2", "Measured ddq2 [rad/s2]"),
                           ("x_d", "Reference x [m]"), ("y_d", "Reference y [m]"),
                           ("dx_d", "Reference dx/dt [m/s]"), ("dy_d", "Reference dy/dt [m/s]"),
                           ("ddx_d", "Reference d2x/dt2 [m/s2]"), ("ddy_d", "Reference d2y/dt2 [m/s2]")):
            d(name, "input", 0.0, text)
        d("tau1", "output", 0.0, "Torque command, chain 1, CCW positive [N m]")
        d("tau2", "output", 0.0, "Torque command, chain 2, CCW positive [N m]")
        d("i_ref1", "output", 0.0, "Current reference tau1/kt1 [A]")
        d("i_ref2", "output", 0.0, "Current reference tau2/kt2 [A]")
        d("e1", "output", 0.0, "Control error, first component (rad or m)")
        d("e2", "output", 0.0, "Control error, second component (rad or m)")
        d("strategy", "parameter", "TCx", "PDq, PDx, TCq, TCx, PDMDq, PDMDx, TCMDq, TCMDx (7.2.6); SMCq, SMCx "
          "(seed 001's sliding modes)")
        d("trajectory", "parameter", "circle", "Which table for joint space: 'circle' (Table 6) or 'triangle' (Table 7)")
        d("lam", "parameter", PRESET_VALUE, "lambda: kp = lam^2, kv = 2 lam (7.29-7.30) [rad/s]; -1: preset")
        d("m_star", "parameter", PRESET_VALUE, "PD inertia m* [kg m2 or kg]; -1: preset")
        d("phi", "parameter", PRESET_VALUE, "Boundary layer phi (6.65); -1: preset")
        d("k1", "parameter", PRESET_VALUE, "Sliding gain k1; -1: preset")
        d("k2", "parameter", PRESET_VALUE, "Sliding gain k2; -1: preset")
        d("gamma1", "parameter", 0.0, "Adaptation rate of k1 (6.66); 0: constant gain")
        d("gamma2", "parameter", 0.0, "Adaptation rate of k2 (6.66); 0: constant gain")
        d("model", "parameter", "tabulated", "'exact' (inverse dynamics 5.74 each step) or 'tabulated' (7.2.5)")
        d("model_error", "parameter", 0.0, "Model masses and inertias are (1 + model_error) times the plant's")
        d("preset", "parameter", "bench", "Plant parameters of the model: 'bench' or 'thesis_sim'")
        d("grid_step", "parameter", DEFAULT_GRID_STEP, "Tabulated model: grid step [m]")
        for name, value in zip(("x_min", "x_max", "y_min", "y_max"), DEFAULT_EXTENT):
            d(name, "parameter", value, f"Tabulated model: grid extent, {name} [m]")
        d("table_fallback", "parameter", True, "Tabulated model: off the table or in a cell with a left-out corner, "
          "use the exact model there (false: refuse the step)")
        d("model_fallbacks", "output", 0, "Samples that used the exact model in place of the table")
        d("cache", "parameter", True, "Tabulated model: load/save the table in the user cache directory")
        d("kt1", "parameter", PRESET_VALUE, "Torque constant of motor 1 [N m/A]; -1: Table 16")
        d("kt2", "parameter", PRESET_VALUE, "Torque constant of motor 2 [N m/A]; -1: Table 18")
        d("T", "parameter", 1e-3, "Sample time [s]; doStep sizes must divide it")
        declare_sample_phase(self)
        d("gravity_x", "parameter", 0.0, "Gravity the model assumes, world x [m/s2]")
        d("gravity_y", "parameter", 0.0, "Gravity the model assumes, world y [m/s2]")
        d("delay_steps", "parameter", 0, "Computation delay: tau1, tau2, i_ref1, i_ref2 are applied this many "
          f"samples after they were computed (0-{MAX_DELAY_STEPS}; the bench: 1)")
        d("delay_compensation", "parameter", 0, "Periods of delay of the measured angles before the commands take "
          f"effect, which the law predicts over with its model (0-{MAX_PREDICT}; 0: none; docs/contract.md)")
        d("velocity_delay_compensation", "parameter", 0, "Periods of delay of the measured rates dq1, dq2 before the "
          f"commands take effect, which the law predicts over (0-{MAX_PREDICT}; 0: none)")
        declare_counter_masses(self)
        self.controller = None
        self.delayed = np.zeros((0, len(OUTPUTS)))

    def setup(self):
        strategy = get_strategy(self.strategy, self.trajectory)
        if not self.T >= MIN_STEP:
            raise ValueError(f"parameter T = {self.T!r} s must be >= {MIN_STEP:g} s")
        numeric = {name: getattr(self, name) for name in NUMERIC_PARAMETERS}
        require_finite(**numeric)
        refuse_absurd(**numeric)
        changes = {}
        for name in ("lam", "m_star", "phi"):
            value = getattr(self, name)
            if value != PRESET_VALUE:
                changes[name] = value
        k = list(strategy.k)
        for i, name in enumerate(("k1", "k2")):
            value = getattr(self, name)
            if value != PRESET_VALUE:
                k[i] = value
        changes["k"] = tuple(k)
        for name in ("gamma1", "gamma2", "kt1", "kt2"):
            value = getattr(self, name)
            if value < 0.0 and not (name.startswith("kt") and value == PRESET_VALUE):
                raise ValueError(f"parameter {name} = {value!r} must be >= 0")
        if self.gamma1 > 0.0 or self.gamma2 > 0.0:
            changes["gamma"] = (self.gamma1, self.gamma2)
        strategy = strategy.with_(**changes)
        self._check_table()
        if not (isinstance(self.delay_steps, int) and 0 <= self.delay_steps <= MAX_DELAY_STEPS):
            raise ValueError(f"parameter delay_steps = {self.delay_steps!r} must be an integer in [0, {MAX_DELAY_STEPS}]")
        # The commands computed but not yet applied, oldest first (changed in place: the
        # compiled loop shares the array).
        self.delayed = np.zeros((self.delay_steps, len(OUTPUTS)))
        for name in ("delay_compensation", "velocity_delay_compensation"):
            value = getattr(self, name)
            if not (isinstance(value, int) and 0 <= value <= MAX_PREDICT):
                raise ValueError(f"parameter {name} = {value!r} must be an integer in [0, {MAX_PREDICT}]")
        from controller.position import default_kt
        kt = tuple(d if v == PRESET_VALUE else v for v, d in zip((self.kt1, self.kt2), default_kt()))
        for name, value in zip(("kt1", "kt2"), kt):
            if not value > 0.0:
                raise ValueError(f"parameter {name} = {value!r} must be > 0 (or -1 for the motor preset's)")
        refuse_tiny(kt1=kt[0], kt2=kt[1])      # i_ref = tau / kt
        params = replace(get_preset(self.preset), gravity=(self.gravity_x, self.gravity_y, 0.0))
        self.controller = _Controller(
            with_counter_masses(self, params), strategy, model=self.model, model_error=self.model_error,
            grid_step=self.grid_step, extent=(self.x_min, self.x_max, self.y_min, self.y_max),
            kt=kt, T=self.T, cache=bool(self.cache), table_fallback=bool(self.table_fallback),
            delay_compensation=(self.delay_compensation, self.velocity_delay_compensation))
        built = getattr(self.controller.model, "build_seconds", 0.0)
        if built:
            self.log(f"{self.instance_name}: the tabulated model was built at initialisation in {built:.2f} s "
                     "(its parameters are not those the FMU was built with, nor in the user's cache)",
                     Fmi2Status.ok, category="logAll")

    def _check_table(self):
        """The tabulated model's grid parameters, named (the model's own messages are about its grid)."""
        if not self.grid_step > 0.0:
            raise ValueError(f"parameter grid_step = {self.grid_step!r} m must be > 0")
        for low, high in (("x_min", "x_max"), ("y_min", "y_max")):
            if not getattr(self, high) > getattr(self, low):
                raise ValueError(f"parameters {low} = {getattr(self, low)!r}, {high} = {getattr(self, high)!r}: "
                                 f"the table's range is empty ({high} must be > {low})")
        points = ((self.x_max - self.x_min) / self.grid_step + 1) * ((self.y_max - self.y_min) / self.grid_step + 1)
        if points > MAX_TABLE_POINTS:
            raise ValueError(f"parameters grid_step = {self.grid_step!r}, x_min = {self.x_min!r}, x_max = {self.x_max!r}, "
                             f"y_min = {self.y_min!r}, y_max = {self.y_max!r} m give a table of {points:.3g} points, "
                             f"more than {MAX_TABLE_POINTS:g} (building it would take initialisation over 10 s)")

    def sample(self, current_time, step_size):
        # One call: outputs and errors together; the controller refuses non-finite outputs
        # (finite but absurd inputs, e.g. a speed of 1e300 rad/s, overflow the law), naming the
        # largest input.
        out = self.controller.step_with_errors(
            current_time, self.q1, self.q2, self.dq1, self.dq2, self.ddq1, self.ddq2,
            self.x_d, self.y_d, self.dx_d, self.dy_d, self.ddx_d, self.ddy_d, self.T)
        if len(self.delayed):
            out = (*delay(self.delayed, out[:4]), *out[4:])   # the queue in C (pc_law_delay), as the compiled loop
        self.tau1, self.tau2, self.i_ref1, self.i_ref2, self.e1, self.e2 = out
        self.model_fallbacks = self.controller.fallbacks
