"""The work one FMI call may do: a deterministic limit, about a second of CPU.

Every ``fmi2DoStep`` of a parcosim FMU counts its work instead of timing it: right-hand-side
evaluations of its integrator, inner steps of a system FMU's components.  Each kind of unit
has a cost [s of CPU], measured once on the development machine by
``benchmarks/call_budget.py`` and rounded up (docs/plant.md, "The work of one call"); a call
may spend :data:`CALL_CPU_SECONDS` of that.  So the limit depends on counts alone: the same
step is refused on every machine and in every run, never because the machine was busy.

* Where the count is known before the step (RK4: 4 evaluations a substep; a system FMU: its
  communication steps times its components' inner steps), a step over the limit is refused
  before anything is done.
* Where it is not (dopri5's adaptive steps), the integrator gets the evaluations left and
  stops there (:class:`plant.integrators.WorkLimitError`); the state is the one before the
  step.

A system FMU's components run inside its call: the first call on a thread opens the budget
(:func:`call_budget`) and the calls inside it spend from the same one.  Refusals are
:class:`CallLimitError`, a ValueError the slave base turns into fmi2Discard with the message
in ``error``.
"""
from __future__ import annotations

import math
import threading
from contextlib import contextmanager

from kernels import timed

#: CPU one FMI call may take [s] (counted, not timed).
CALL_CPU_SECONDS = 1.0

# Costs of one unit of work [s of CPU] (benchmarks/call_budget.py; measured and chosen values
# in docs/plant.md).
#: One right-hand side of the compiled 5R RK4 (FiveBarPlant and ActuatedFiveBarPlant,
#: kernel 'fast', the drives' currents included).
FAST_RK4_EVALUATION = 1.5e-6
#: One right-hand side of dopri5 on the compiled 5R right-hand side (kernel 'fast'), with the
#: drives' terms of ActuatedFiveBarPlant and dopri5's own arithmetic.
FAST_DOPRI5_EVALUATION = 25e-6
#: One right-hand side of the general algorithm (5.66) in numpy (FiveBarPlant and
#: ActuatedFiveBarPlant with kernel 'general', SpecPlant; either integrator): this much ...
GENERAL_EVALUATION_BASE = 1.0e-3
#: ... plus this much per joint of the mechanism's chains (the 5R: 4; the spec delta3: 9).
GENERAL_EVALUATION_PER_JOINT = 250e-6
#: One right-hand side of the wheeled pendulum's compiled RK4.
WHEELED_RK4_EVALUATION = 0.1e-6
#: One inner doStep of a component inside a system FMU (ClosedLoop, ControlChain): the
#: stepper's exchange and the component's own step; a plant's evaluations are charged on top.
INNER_STEP = 15e-6


class CallLimitError(ValueError):
    """A step refused because it needs more work than one call may do (the message says what)."""


def per_call(unit: float) -> int:
    """How many units of cost ``unit`` one call may take."""
    return math.floor(CALL_CPU_SECONDS / unit)


def plant_evaluation_cost(kernel: str, method: str, joints: int) -> float:
    """The cost of one right-hand side of a mechanism with ``joints`` joints integrated by
    ``method`` ('rk4' or 'dopri5') with ``kernel`` ('fast': the compiled 5R, or 'general')."""
    if kernel == "fast":
        return FAST_RK4_EVALUATION if method == "rk4" else FAST_DOPRI5_EVALUATION
    return GENERAL_EVALUATION_BASE + joints * GENERAL_EVALUATION_PER_JOINT


def short(seconds: float) -> str:
    """``seconds`` as '1.2 ms', '40 µs' (for messages)."""
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.2g} ms"
    return f"{seconds * 1e6:.2g} µs"


class CallBudget:
    """The CPU one call has left [s], spent by counts times unit costs."""

    def __init__(self):
        self.total = self.left = CALL_CPU_SECONDS

    @property
    def fresh(self) -> bool:
        """Nothing spent yet: the whole call's budget is left."""
        return self.left == self.total

    def count_left(self, unit: float) -> int:
        """How many units of cost ``unit`` fit in what is left."""
        return max(0, math.floor(self.left / unit))

    def limit_text(self, unit: float) -> str:
        """'the N one call may take (~1 s of CPU)', or what is left of it inside a system FMU."""
        n = self.count_left(unit)
        if self.fresh:
            return f"the {n:.6g} one call may take (~{self.total:g} s of CPU)"
        return f"the {n:.6g} left of this call's ~{self.total:g} s of CPU (the rest went to the other components)"

    def require(self, count: int, unit: float, what: str, cause: str, advice: str = "") -> None:
        """Refuse (:class:`CallLimitError`) work of ``count`` units of cost ``unit`` that does not
        fit: '<cause> needs <count> <what> (~<unit> each), more than <limit>; <advice>'."""
        if count * unit <= self.left:
            return
        raise timed(CallLimitError(f"{cause} needs {count:.6g} {what} (~{short(unit)} each), more than "
                                   f"{self.limit_text(unit)}" + (f"; {advice}" if advice else "")))

    def spend(self, seconds: float) -> None:
        self.left -= seconds


class _Active(threading.local):
    """This thread's budget; None (the class's) until a call sets one: read without the
    AttributeError a missing one would raise (every plant step asks)."""

    budget = None


_active = _Active()


def active() -> CallBudget | None:
    """The budget of the call running on this thread, None outside any counted call."""
    return _active.budget


@contextmanager
def call_budget():
    """The budget of the FMI call running on this thread: a new one in the outermost call, the
    enclosing system FMU's inside it."""
    budget = active()
    if budget is not None:
        yield budget
        return
    _active.budget = budget = CallBudget()
    try:
        yield budget
    finally:
        _active.budget = None


def bounded_integration(run, unit: float, known: int | None, what: str, current_time: float, step_size: float,
                        advice: str = "") -> int:
    """Run ``run(max_evaluations)`` (returning the evaluations it took) within this call's budget.

    ``known``: the evaluations the step takes, when known before it (RK4): refused before it
    starts when they do not fit.  None (dopri5): ``run`` gets the evaluations left and raises
    :class:`plant.integrators.WorkLimitError` at them, its state unchanged; that becomes a
    :class:`CallLimitError` naming the step size, the time, the evaluations and the limit.
    """
    if known is not None and known * unit <= CALL_CPU_SECONDS and active() is None:
        return run(None)        # fits a whole call, and no system FMU shares it
    from plant.integrators import WorkLimitError

    cause = f"step size h = {step_size!r} s at t = {current_time!r} s"
    with call_budget() as budget:
        if known is not None:
            budget.require(known, unit, what, cause, advice)
            evaluations = run(None)
        else:
            try:
                evaluations = run(budget.count_left(unit))
            except WorkLimitError as exc:
                raise timed(CallLimitError(
                    f"{cause} needs more {what} (~{short(unit)} each) than {budget.limit_text(unit)}: dopri5 "
                    f"stopped after {exc.evaluations}, {exc.reached:.3g} s into the step; nothing changed"
                    + (f"; {advice}" if advice else ""))) from None
        budget.spend(evaluations * unit)
        return evaluations


# --- the plants' integrators ---------------------------------------------------------------------

def joints_of(mechanism) -> int:
    """The joints of a parallel mechanism's chains (:class:`plant.parallel.ParallelMechanism`)."""
    return sum(len(chain.joints) for chain in mechanism.chains)


def plant_work(sim) -> tuple:
    """(cost of one right-hand side, evaluations of a step when known before it or None, what
    they are in words, advice) of a plant simulator (:class:`plant.PlantSimulator`,
    :class:`plant.specsim.SpecSimulator`) with its integrator settings."""
    s = sim.settings
    unit = plant_evaluation_cost(s.kernel, s.method, joints_of(sim.mechanism))
    what = f"right-hand-side evaluations ({s.kernel} kernel, {s.method})"
    if s.method == "rk4":
        return unit, 4 * s.substeps, what, "take shorter steps or use fewer substeps"
    from plant import PlantSimulator

    faster = " or use kernel 'fast'" if s.kernel != "fast" and isinstance(sim, PlantSimulator) else ""
    return unit, None, what, f"take shorter steps, loosen rtol = {s.rtol!r} / atol = {s.atol!r}{faster}"


def step_plant(sim, run, current_time: float, step_size: float) -> int:
    """``run(max_evaluations)``, one step of the plant simulator ``sim``, within this call's
    budget (:func:`bounded_integration`).  An RK4 step outside a system FMU runs as it is: its
    count fits a whole call (:func:`check_rk4_substeps` at initialisation)."""
    if sim.settings.method == "rk4" and active() is None:
        return run(None)
    unit, known, what, advice = plant_work(sim)
    return bounded_integration(run, unit, known, what, current_time, step_size, advice)


def known_step_work(sim) -> float:
    """The least CPU [s] one step of ``sim`` is charged: RK4's evaluations, dopri5's first
    attempt (7 evaluations)."""
    unit, known, _, _ = plant_work(sim)
    return unit * (known if known is not None else 7)


def check_rk4_substeps(sim, parameters: str, alternative: str) -> None:
    """Refuse (:class:`CallLimitError`, at initialisation) RK4 ``substeps`` whose 4 evaluations
    a substep do not fit one call: '<parameters>: a doStep needs N right-hand-side evaluations
    (~cost each), more than the M allowed per call (~1 s of CPU); use substeps <= K or <alternative>'."""
    s = sim.settings
    unit, known, what, _ = plant_work(sim)
    if s.method != "rk4" or known * unit <= CALL_CPU_SECONDS:
        return
    limit = per_call(unit)
    raise CallLimitError(f"{parameters}: a doStep needs {known} {what} (~{short(unit)} each), more than the "
                         f"{limit} allowed per call (~{CALL_CPU_SECONDS:g} s of CPU); use substeps <= "
                         f"{max(1, limit // 4)} or {alternative}")
