"""Sub-stepping of sampled components: steps h = T / n, one sample per period T.

A sampled component (derivator, position controller, balance controller, current observer;
the drive's current controller counts its sub-steps in its C kernel, :mod:`motor.drive`)
accepts any communication step h that divides its sample time T (n = T / h a whole number,
1e-9 relative).  It counts its steps since initialisation in the period, k = 0 ... n - 1, an
integer (never ``fmod`` of the time, which drifts when a tool accumulates t + h), and takes
its sample on the step k = ``sample_phase`` of each period: that step's ``doStep(t, h)``
reads the inputs at t and computes the outputs the model computes at h = T; the other steps
hold them (a model whose state moves between samples, the dynamic observer, advances it).  ``sample_phase`` = 0 (the default) samples at each period's start: with h = T
every step samples, as before sub-stepping existed.

``hold_first_step`` (Boolean, default false): the run's first step (the one from
fmi2SetupExperiment's start time) does not sample, whatever its phase; the outputs hold their start values over it and the first sample is the next one
of the phase (at h = T: the second step).  A Jacobi master that feeds 0.0 to every input on
its first step instead of the outputs after initialisation (fmpy's ``simulate_ssp``) then
cannot put those zeros into the model: the per-component export sets it on the instances
that would sample on the first step (docs/ssp.md).

The step size may change only at a period's start (k = 0), to another divisor of T; within
a period a step whose T / h differs is refused, naming h, T and the time.  The counter is
FMU state (``_substep``, ``_substeps`` are plain attributes: :mod:`fmus.slave.state` keeps
them), so a state restored mid-period goes on exactly.

The rule of the step sizes (n = T / h with its tolerance and rounding, the period change) is
C, ``kernels/src/pc_sampling.c``, which the drive's kernel and the native FMUs use too.  Per
step, :meth:`SampledSteps.step` does pc_sampling's two integer comparisons in Python: two
ctypes calls would make a sampled slave's step (h = T / 4) 2.1 to 3.5 times as slow
(``benchmarks/bench_sampling_counting.py``).
"""
from __future__ import annotations

import ctypes

from pythonfmu import DefaultExperiment

import kernels
from fmus.slave.base import GuardedSlave

_d = ctypes.c_double
_SUBSTEPS = kernels.function("pc_sampling_substeps", _d, _d, _d)
_CHANGES_PERIOD = kernels.function("pc_sampling_changes_period", ctypes.c_int, _d, _d, _d)

#: The phase parameter's name (docs/contract.md): the sub-step of each period that samples.
PHASE_PARAMETER = "sample_phase"
#: The Boolean parameter (docs/contract.md): the run's first step does not sample.
HOLD_FIRST_PARAMETER = "hold_first_step"
#: Relative tolerance of "h divides T": |T / h - n| <= SAMPLE_TOLERANCE n (pc_sampling.h's
#: PC_SAMPLING_TOLERANCE, which decides).
SAMPLE_TOLERANCE = 1e-9


def declare_sample_phase(slave) -> None:
    """Declare the Integer parameter ``sample_phase`` (start 0)."""
    slave.declare(PHASE_PARAMETER, "parameter", 0,
                  "Sub-step of each period that samples: with steps h = T / n, the sample is taken on the step "
                  "starting sample_phase * h after each period's start (0 <= sample_phase < n; 0: at the start)")


def substeps_of(T: float, h: float) -> int | None:
    """n = T / h when h divides T (a whole number n >= 1, 1e-9 relative), else None."""
    whole = _SUBSTEPS(T, h)
    return int(whole) if whole else None


def checked_substeps(slave, current_time: float, step_size: float) -> int:
    """n = T / h of a step the sampled ``slave`` can take with its ``sample_phase``; a
    ValueError naming h, T and t (and the phase) otherwise."""
    n = substeps_of(slave.T, step_size)
    if n is None:
        raise ValueError(slave.step_size_message(current_time, step_size,
                                                 f"does not divide the sample time T = {slave.T!r} s"))
    check_phase(slave, current_time, step_size, n)
    return n


def check_phase(slave, current_time: float, step_size: float, n: int) -> None:
    """Raise ValueError unless ``slave.sample_phase`` is a whole number in [0, n)."""
    phase = getattr(slave, PHASE_PARAMETER)
    if not (isinstance(phase, int) and 0 <= phase < n):
        raise ValueError(f"parameter {PHASE_PARAMETER} = {phase!r} must be a whole number in [0, T / h) = [0, {n}) "
                         f"for the step size h = {step_size!r} s at t = {current_time!r} s (T = {slave.T!r} s)")


def check_period_change(slave, current_time: float, step_size: float, n: int, counted: int, substep: int) -> None:
    """Raise ValueError if T / h changes (``counted`` -> ``n``) within a period (``substep`` > 0)."""
    if _CHANGES_PERIOD(substep, counted, n):
        raise ValueError(f"step size h = {step_size!r} s at t = {current_time!r} s changes the step within a "
                         f"sample period (T = {slave.T!r} s, sub-step {substep} of {counted}, steps of "
                         f"{slave.T / counted!r} s): {type(slave).__name__} accepts a new step size only at a "
                         "period's start")


def model_description_with_period(slave, to_xml, model_options):
    """``to_xml(model_options)`` (pythonfmu's modelDescription.xml) with the DefaultExperiment's
    stepSize the slave's sample time T (as built: its start value): what a tool that reads
    it (fmpy's ``simulate_fmu`` without a step) steps by."""
    slave.default_experiment = DefaultExperiment(start_time=0.0, step_size=slave.T)
    return to_xml(model_options)


def accepted_steps_text() -> str:
    """The sub-stepping rule, in words (refusals, docs/extremes.md)."""
    return (f"h dividing the sample time T (T / h = n a whole number, 1e-9 relative), the same n within a "
            f"period; it samples on sub-step {PHASE_PARAMETER} (0 <= {PHASE_PARAMETER} < n) of each period and "
            "holds its outputs in between")


class SampledSteps:
    """Mixin (before :class:`fmus.slave.base.GuardedSlave`) of a component sampled at ``T``.

    The slave declares ``T`` and :func:`declare_sample_phase`, and defines
    :meth:`sample` (the model's step at the sample, over the period T) and, if its state
    moves between samples, :meth:`between_samples`.
    """

    sampled = True
    #: Steps must divide a period T, changed only at a period's start: the FMU declares
    #: canHandleVariableCommunicationStepSize="false" and DefaultExperiment stepSize T.
    has_sample_period = True

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.declare(HOLD_FIRST_PARAMETER, "parameter", False,
                     "The run's first step does not sample: the outputs hold their start values over it (a master "
                     "that feeds 0.0 to every input on its first step cannot reach the model); the first sample is "
                     "the phase's next")
        self._substep = 0     # the next step's index in its period
        self._substeps = 0    # n = T / h of the steps counted (0: none yet)

    def exit_initialization_mode(self):
        self._substep = self._substeps = 0
        return super().exit_initialization_mode()

    def accepted_steps(self):
        return accepted_steps_text()

    def to_xml(self, model_options=None):
        return model_description_with_period(self, super().to_xml, model_options or {})

    def check_step_size(self, current_time, step_size):
        GuardedSlave.check_step_size(self, current_time, step_size)   # T itself is checked by setup
        n = checked_substeps(self, current_time, step_size)
        check_period_change(self, current_time, step_size, n, self._substeps, self._substep)
        self._substeps = n

    def step(self, current_time, step_size):
        k = self._substep   # pc_sampling_samples and pc_sampling_next, in Python (module docstring)
        if k == self.sample_phase and not (self.hold_first_step and current_time == self._start_time):
            self.sample(current_time, step_size)
        else:
            self.between_samples(current_time, step_size)
        self._substep = k + 1 if k + 1 < self._substeps else 0

    def sample(self, current_time: float, step_size: float) -> None:
        """Take the sample at ``current_time`` (the model's step of a period T; ``step_size``
        is this step's h)."""
        raise NotImplementedError

    def between_samples(self, current_time: float, step_size: float) -> None:
        """A step that does not sample: the outputs hold (a model with a state between
        samples advances it here)."""
