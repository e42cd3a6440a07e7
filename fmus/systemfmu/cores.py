"""A system of parcosim components inside one FMU.

Two shapes, both built per scene by :mod:`fmus.systemfmu.export` with the system written into the
FMU's resources (``system.json``), both stepping the components in process with the
master's own :class:`fmus.cosim.stepper.Stepper`:

* :class:`LoopCore` (FMU ``ClosedLoop``): the whole closed loop, stepped exactly as
  :func:`fmus.cosim.master.simulate` steps it (Gauss-Seidel, the same order): the FMU's run is
  the master's run.
* :class:`ChainCore` (FMU ``ControlChain``): everything but the plant, for a package whose
  plant is another FMU instance stepped by a Jacobi master (Ecos, libcosim, fmpy's SSP
  runner).  There every value crosses between the two instances one communication step
  late: the chain reads the plant's outputs at t_k and the plant applies, over
  [t_k, t_k+1], what the chain published at t_k.  So the chain computes one sample
  ahead: in its step from t_k it takes the sample of t_k+1, with the plant's outputs at
  t_k+1 predicted by a model of the plant run beside the real one (the system's own
  plant component, whose parameters are the chain's model of the plant).  Before each
  prediction the model is corrected by the measurement of t_k
  (:func:`plant.correction.corrected_state`).  Where model and plant agree, the
  prediction is exact and the package runs the loop of the master, with the plant
  given exactly what the master would give it.
"""
from __future__ import annotations

import json
import math

from plant.correction import MEASURABLE

from fmus.slave import budget
from fmus.cosim.backends import _CONVERT, CoSimulationError, InProcessInstance
from fmus.cosim.master import stepping_order
from fmus.cosim.stepper import Stepper
from fmus.cosim.system import Component, Connection, System, split_signal
from fmus.status import RunError
from kernels import timed

SYSTEM_FILE = "system.json"


# --- the system as data ---------------------------------------------------------------------

def system_to_dict(system: System) -> dict:
    """``system`` as JSON-ready data (:func:`system_from_dict` reads it back)."""
    return {"components": [{"name": c.name, "model": c.model, "parameters": dict(c.parameters),
                            "substeps": c.substeps} for c in system.components],
            "connections": [[c.source, c.target] for c in system.connections],
            "record": list(system.record), "stop_time": system.stop_time, "step": system.step}


def system_from_dict(data: dict) -> System:
    """The :class:`System` of :func:`system_to_dict`'s data."""
    return System(tuple(Component(c["name"], c["model"], dict(c["parameters"]), int(c["substeps"]))
                        for c in data["components"]),
                  tuple(Connection(s, t) for s, t in data["connections"]),
                  tuple(data["record"]), float(data["stop_time"]), float(data["step"]))


def component_parameters(system: System) -> dict:
    """``"instance.parameter"`` -> value for every parameter of every component: the
    system's value where it sets one, else the component's default (its start value).
    A component given as an FMU file (:mod:`fmus.cosim.foreign`) has the parameters of its
    model description; the system's values it lacks are left out."""
    from fmus.cosim.foreign import is_fmu_file

    result = {}
    for c in system.components:
        if is_fmu_file(c.model):
            defaults = _fmu_parameters(c.model)
        else:
            inst = InProcessInstance(c.model, c.name)
            defaults = {v.name: (v.type, getattr(inst.slave, v.name)) for v in inst.variables.values()
                        if v.causality == "parameter"}
        for name, (type_, default) in defaults.items():
            result[f"{c.name}.{name}"] = _CONVERT[type_](c.parameters.get(name, default))
    return result


def _fmu_parameters(path) -> dict:
    """Name -> (type, start value) of an FMU file's parameters."""
    from fmpy import read_model_description

    md = read_model_description(str(path), validate=False)
    result = {}
    for v in md.modelVariables:
        if v.causality == "parameter" and v.start is not None:
            start = v.start
            if v.type == "Boolean" and isinstance(start, str):
                start = start.strip() in ("true", "1")
            result[v.name] = (v.type, start)
    return result


#: Where a system FMU keeps the FMU files of its foreign components, in its resources.
FOREIGN_DIR = "foreign"


def with_parameters(system: System, values: dict) -> System:
    """``system`` with its components' parameters taken from ``values``
    (``"instance.parameter"`` -> value, as :func:`component_parameters`)."""
    components = []
    for c in system.components:
        prefix = f"{c.name}."
        own = {name[len(prefix):]: value for name, value in values.items() if name.startswith(prefix)}
        components.append(Component(c.name, c.model, {**c.parameters, **own}, c.substeps))
    return System(tuple(components), system.connections, system.record, system.stop_time, system.step)


def _in_process(system: System) -> Stepper:
    """Our components in process, FMU files through fmpy (the master's back ends)."""
    from fmus.cosim.foreign import without_missing_parameters
    from fmus.cosim.master import _instantiate

    instances = _instantiate(system, "inprocess", None)
    system, _ = without_missing_parameters(system, {n: set(i.variables) for n, i in instances.items()})
    order = stepping_order(system, {n: inst.variables for n, inst in instances.items()})
    return SystemStepper(system, instances, order)


# --- refusals of the components --------------------------------------------------------------

class InitialisationRefused(CoSimulationError):
    """A component of a system inside an FMU refused its initialisation."""

    def __str__(self):
        return f"{self.instance}: {self.message}"


class SystemStepper(Stepper):
    """The :class:`fmus.cosim.stepper.Stepper` of a system inside an FMU.

    A component's refusal stays in the component's words: who refused is the record's
    ``instance`` (``<FMU instance>.<component>``, :func:`fmus.status.refusal_of`), and the
    message names the component.  A component that refused its initialisation refuses the
    system's (:class:`InitialisationRefused`): no step, no sample is taken from a component
    that has no model (the ControlChain's first sample read its plant model's state, and
    failed with "'NoneType' object has no attribute 'y'").
    """

    def initialize(self, start_time: float = 0.0) -> None:
        super().initialize(start_time)
        for name, inst in self.instances.items():
            slave = getattr(inst, "slave", None)        # an in-process slave's refusal, in its own words
            if slave is not None and slave.error:
                raise InitialisationRefused(name, start_time, slave.refused_because or slave.error,
                                            RunError.from_json(slave.refusal))


def _steps_in(time: float, current_time: float, step_size: float, h: float, multiples: bool) -> int:
    """How many communication steps h a ``doStep(current_time, step_size)`` takes; a
    ValueError for a step size that is not h (or, with ``multiples``, a whole multiple of
    it) or a communication point that does not follow the last one (``time``)."""
    n = round(step_size / h) if math.isfinite(step_size) and step_size > 0.0 else 0
    if n < 1 or (n > 1 and not multiples) or not math.isclose(step_size, n * h, rel_tol=1e-9, abs_tol=0.0):
        allowed = f"a whole multiple of h = {h!r} s" if multiples else f"h = {h!r} s"
        raise timed(ValueError(f"step size {step_size!r} s at t = {current_time:.6g} s: this FMU steps its "
                               f"system at its communication step; the step size must be {allowed}"))
    if not math.isclose(current_time, time, rel_tol=0.0, abs_tol=1e-6 * h):
        raise timed(ValueError(f"communication point t = {current_time!r} s does not follow the last one "
                               f"({time!r} s)"))
    return n


def inner_work(stepper: Stepper, extra=()) -> tuple:
    """(inner doSteps, their least CPU [s]) of one communication step of ``stepper``'s system:
    each component's sub-steps at :data:`fmus.slave.budget.INNER_STEP` plus what its slave states it
    charges for a step (``known_step_work()``: a plant's RK4 evaluations); an FMU-file
    component, which bounds its own calls, at INNER_STEP.  ``extra``: instance names stepped once
    more (a corrected model of the plant)."""
    count, seconds = 0, 0.0
    for entry in stepper.plan:
        known = getattr(getattr(entry.instance, "slave", None), "known_step_work", None)
        repeats = entry.substeps + extra.count(entry.name)
        count += repeats
        seconds += repeats * (budget.INNER_STEP + (known() if known is not None else 0.0))
    return count, seconds


# --- the whole loop ------------------------------------------------------------------------

class LoopCore:
    """``system`` stepped in process, one communication step per :meth:`step`: the master's
    run (:func:`fmus.cosim.master.simulate`, mode "inprocess", Gauss-Seidel)."""

    def __init__(self, system: System):
        self.system = system
        self.stepper = _in_process(system)

    def initialize(self) -> None:
        self.stepper.initialize(0.0)

    def step(self, current_time: float, step_size: float) -> None:
        """``step_size`` / h communication steps; refusals name the inner component."""
        for _ in range(_steps_in(self.stepper.time, current_time, step_size, self.system.step, True)):
            self.stepper.step()

    def work_per_step(self) -> tuple:
        """(inner doSteps, their least CPU [s]) of one communication step (:func:`inner_work`)."""
        return inner_work(self.stepper)

    def inner_steps(self) -> int:
        """The inner doSteps of one communication step."""
        return sum(entry.substeps for entry in self.stepper.plan)

    def value(self, signal: str) -> float:
        return self.stepper.value(signal)

    def state(self) -> dict:
        """The loop's state: the stepper's (time, values, every inner slave's state)."""
        return self.stepper.state()

    def restore(self, state: dict) -> None:
        self.stepper.restore(state)


# --- the control chain of a package ----------------------------------------------------------

def chain_interface(system: System, plant: str = "plant"):
    """What the chain of ``system`` exchanges with its plant ``plant``.

    Returns
    -------
    measured : tuple of str
        The plant's outputs the other components read that a real plant measures
        (:data:`plant.correction.MEASURABLE`: angles, encoder readings, speeds): the
        chain's inputs.  What else they read of the plant (the voltage it applied, which
        the chain itself commanded) comes from the model.
    commanded : dict
        Plant input -> where the chain finds its value: ``tau1`` -> the signal connected to
        it; for an ``ActuatedFiveBarPlant`` ``v_ref<j>`` -> its output ``v<j>``, the
        voltage its current controllers applied (the real plant runs in voltage mode).
    """
    measured, commanded = [], {}
    for c in system.connections:
        src, out = split_signal(c.source)
        dst, inp = split_signal(c.target)
        if src == plant and dst != plant and out in MEASURABLE and out not in measured:
            measured.append(out)
        if dst == plant and src != plant:
            commanded[inp] = c.source
    if system.component(plant).model == "ActuatedFiveBarPlant":
        commanded = {f"v_ref{j}": f"{plant}.v{j}" for j in ("1", "2")}
    return tuple(measured), commanded


class ChainCore:
    """The components of ``system`` stepped one sample ahead of a real plant, with the
    system's plant component as the model that predicts it (module docstring).

    ``zero_start`` (default): the plant's first step [0, h] is commanded zero (0 V, or
    0 N m), in the model and in the plant, and the controllers' first sample is that of h:
    the same run whether the master passes the outputs after initialisation to the first
    step (Ecos, libcosim) or zeros (fmpy's SSP runner).  False: the sample of t = 0
    commands the first step, as in our master, in masters that pass those outputs.

    After :meth:`initialize` and after each :meth:`step` from t_k, :meth:`command` gives
    what the real plant is to apply over the next step [t_k+1, t_k+2] (the sample of
    t_k+1), and :meth:`recorded` the system's other signals at t_k+1 as the master
    records them.
    """

    def __init__(self, system: System, plant: str = "plant", zero_start: bool = True):
        self.system, self.plant, self.zero_start = system, plant, zero_start
        self.measured, self.commanded = chain_interface(system, plant)
        self.stepper = _in_process(system)
        self.model = self.stepper.instances[plant]
        self.corrections = 0
        self._row, self._snapshot, self._time = None, None, 0.0

    def initialize(self) -> None:
        """Initialise the components and take the sample of t = 0; with ``zero_start`` the
        plant's first step is commanded zero instead, in the model as in the plant."""
        self.stepper.initialize(0.0)
        if self.zero_start:
            self.model.slave.idle_steps = 1
        self._advance()

    def _advance(self) -> None:
        self._row = dict(zip(self.system.record, self.stepper.row()))
        self._snapshot = self.model.slave.snapshot()
        self.stepper.step()

    def step(self, current_time: float, step_size: float, measured: dict) -> None:
        """The step from t_k = ``current_time``: correct the model by the plant's outputs
        ``measured`` at t_k (not at the first step: the plant's initial state is the
        model's, and some masters pass zeros there), then take the sample of t_k+1."""
        h = self.system.step
        _steps_in(self._time, current_time, step_size, h, multiples=False)
        for name, value in measured.items():
            if not math.isfinite(value):
                raise timed(ValueError(f"input {name} = {value!r} at t = {current_time:.6g} s is not finite"))
        if current_time > 0.5 * h:
            try:
                corrected = self.model.slave.correct(self._snapshot, measured, h)
            except Exception as exc:  # noqa: BLE001 - a plant refusal, named as the chain's
                raise CoSimulationError(self.plant, current_time, f"the plant model cannot follow the "
                                        f"measurement {measured}: {exc}") from None
            if corrected:
                self.corrections += 1
                self.stepper.refresh(self.model)
        self._advance()
        self._time = current_time + h

    def work_per_step(self) -> tuple:
        """(inner doSteps, their least CPU [s]) of one step: the components' and the model's
        corrected step (:func:`inner_work`)."""
        return inner_work(self.stepper, extra=(self.plant,))

    def inner_steps(self) -> int:
        """The inner doSteps of one step, the model's corrected step included."""
        return sum(entry.substeps for entry in self.stepper.plan) + 1

    def state(self) -> dict:
        """The chain's state: the stepper's, the row and snapshot of the sample ahead, the
        time of the next step and the count of corrections."""
        return {"stepper": self.stepper.state(), "row": self._row, "snapshot": self._snapshot,
                "time": self._time, "corrections": self.corrections}

    def restore(self, state: dict) -> None:
        self.stepper.restore(state["stepper"])
        self._row, self._snapshot = state["row"], state["snapshot"]
        self._time, self.corrections = state["time"], state["corrections"]

    def command(self) -> dict:
        """What the plant is to apply over its next step."""
        if self.zero_start and self._time == 0.0:     # the first step: what the model applied
            return {name: 0.0 for name in self.commanded}
        return {name: self.stepper.value(signal) for name, signal in self.commanded.items()}

    def recorded(self) -> dict:
        return self._row


def read_system(resources: str) -> tuple:
    """(System, role, plant name) from an FMU's ``resources/system.json``."""
    import os

    with open(os.path.join(resources, SYSTEM_FILE), encoding="utf-8") as f:
        data = json.load(f)
    for c in data["system"]["components"]:      # foreign FMUs travel in the resources
        if c["model"].startswith(FOREIGN_DIR + "/"):
            c["model"] = os.path.join(resources, c["model"])
    return system_from_dict(data["system"]), data["role"], data.get("plant", "plant")
