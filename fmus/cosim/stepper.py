"""A system's instances stepped one communication step at a time.

:class:`Stepper` is the loop of :func:`fmus.cosim.master.simulate`, cut at the step: built
from the instances and their stepping order, it initialises them, then each
:meth:`Stepper.step` advances every instance by one communication step and updates
the values of the signals that are read or recorded.  The master runs a whole system
with it; an FMU that contains a system (:mod:`fmus.systemfmu.cores`) steps it in its
``doStep``.  The semantics (coupling, multi-rate groups, rows) are the master's: see
:mod:`fmus.cosim.master`.
"""
from __future__ import annotations

import operator

from fmus.cosim.backends import CoSimulationError
from fmus.cosim.slots import gatherer as _gatherer
from fmus.cosim.slots import span as _span
from fmus.cosim.system import System, split_signal


def member_calls(inst, in_slots, out_slots) -> tuple:
    """What one communication step of ``inst`` takes from the stepper's values:
    (pull(values) or None, step(t, h), read, source, out, inst).  ``pull`` sets the inputs
    from the slots ``in_slots``; ``step`` steps (False: refused, ``inst.step_refused(t)`` says
    why); ``values[out] = read(source)`` stores the outputs (``out`` a slice, or an index for
    one output read as a value).  An instance offers its own (``inst.step_calls``: the
    in-process slaves' attributes moved without a Python call: its class's, so that a wrapper
    delegating its attributes, whose ``do_step`` is another, is not bypassed); otherwise its
    ``set_inputs``, ``do_step`` and ``get_outputs``.  :mod:`benchmarks.bench_master` times these."""
    own = getattr(type(inst), "step_calls", None)
    if own is not None:
        return own(inst, in_slots, out_slots)
    pull = None
    if in_slots:
        gather, set_inputs = _gatherer(in_slots), inst.set_inputs

        def pull(values):
            set_inputs(gather(values))
    return pull, inst.do_step, operator.call, inst.get_outputs, _span(out_slots), inst


def rate_groups(plan) -> list:
    """Consecutive plan entries of equal sub-step count > 1 form one group:
    [(substeps, [(instance, input slots, output slots), ...]), ...]."""
    groups = []
    for inst, in_slots, out_slots, substeps in plan:
        if substeps > 1 and groups and groups[-1][0] == substeps:
            groups[-1][1].append((inst, in_slots, out_slots))
        else:
            groups.append((substeps, [(inst, in_slots, out_slots)]))
    return groups


def _exchanges_of(groups) -> list:
    """Per group of :func:`rate_groups`: [(instance, its inputs' gatherer or None, its outputs'
    slice)] (a split step's groups differ from the plan's: it needs its own)."""
    return [[(inst, _gatherer(ins) if ins else None, _span(outs)) for inst, ins, outs in members]
            for _, members in groups]


class Stepper:
    """Instances of ``system`` wired together, stepped in ``order``.

    Parameters
    ----------
    system : System
    instances : dict
        Instance name -> back-end instance (``fmus.cosim.master.InProcessInstance`` or an FMU
        instance): ``variables``, ``bind``, ``initialize``, ``set_inputs``,
        ``get_outputs``, ``do_step``; ``get_state``, ``set_state`` for :meth:`state`.
    order : sequence of str
        The stepping order (Gauss-Seidel) or the listing order (Jacobi).
    jacobi : bool
        Every instance reads the values all held at the step's start.

    Raises
    ------
    ValueError
        A recorded signal that is neither an output nor a connected input.
    """

    #: Each member's calls (:func:`member_calls`) when one flat loop steps the system, else None.
    _members = None

    def __init__(self, system: System, instances: dict, order, jacobi: bool = False):
        self.system, self.instances, self.order, self.jacobi = system, instances, tuple(order), jacobi
        self.slots = {}
        feeds = {c.name: [] for c in system.components}
        for conn in system.connections:
            feeds[split_signal(conn.target)[0]].append(conn)
        sources = [c.source for c in system.connections]
        produced = {}
        for name in self.order:
            inst = instances[name]
            signals = [s for s in sources + list(system.record)
                       if split_signal(s)[0] == name and inst.variables[split_signal(s)[1]].causality == "output"]
            produced[name] = list(dict.fromkeys(signals))
            for signal in produced[name]:   # slots of the outputs first: each instance's are one slice
                self._slot(signal)
        plan = []
        #: Instance name -> (its connected inputs, the outputs it produces), as bound.
        self.io_names = {}
        for name in self.order:
            inst = instances[name]
            in_vars = [inst.variables[split_signal(c.target)[1]] for c in feeds[name]]
            in_slots = [self._slot(c.source) for c in feeds[name]]
            inst.bind(in_vars, [inst.variables[split_signal(s)[1]] for s in produced[name]])
            self.io_names[name] = ([v.name for v in in_vars], [split_signal(s)[1] for s in produced[name]])
            plan.append((inst, in_slots, [self.slots[s] for s in produced[name]], system.component(name).substeps))
        record_inputs = [s for s in system.record if s not in self.slots]
        if record_inputs:
            raise ValueError(f"recorded signals must be outputs or connected inputs: {record_inputs}")
        self.record_slots = [self.slots[s] for s in system.record]
        self._record = _gatherer(self.record_slots)
        self.plan = plan
        self.groups = rate_groups(plan)
        self._exchanges = _exchanges_of(self.groups)
        # Gauss-Seidel at one rate (the usual system): one flat loop over the members' calls.
        self._members = None if jacobi or any(n > 1 for n, _ in self.groups) else \
            tuple(member_calls(inst, ins, outs) for inst, ins, outs, _ in plan)
        self.values = [0.0] * len(self.slots)
        self.time = 0.0

    def _slot(self, signal):
        return self.slots.setdefault(signal, len(self.slots))

    def initialize(self, start_time: float = 0.0) -> None:
        """Initialise every instance with its component's parameters and its connected inputs.

        All instances enter initialisation mode and get their parameters; then, in the
        order of :meth:`initialization_order`, each gets its connected inputs (from the
        outputs its sources hold: after their initialisation for sources that left it, their
        values in initialisation mode for the others), leaves initialisation mode, and its
        outputs are read.  So the t = 0 row is consistent: an output that depends on an input
        was computed from the connected value, not from the input's start value.
        """
        for c in self.system.components:
            self.instances[c.name].enter_initialization(c.parameters, start_time)
        self.time = start_time
        for inst, _, out_slots, _ in self.plan:
            self.refresh(inst, out_slots)
        values = self.values
        for inst, in_slots, out_slots, _ in self.initialization_order():
            if in_slots:
                inst.set_inputs([values[i] for i in in_slots])
            inst.exit_initialization()
            self.refresh(inst, out_slots)

    def initialization_order(self) -> list:
        """The plan's entries in the order instances leave initialisation mode: every
        source before its readers where the connections allow it; in a loop, the first
        instance in the stepping order (which keeps every sampled or feedthrough source
        before its readers) goes first."""
        sources = {name: set() for name in self.order}
        for conn in self.system.connections:
            src, dst = split_signal(conn.source)[0], split_signal(conn.target)[0]
            if src != dst:
                sources[dst].add(src)
        entries = dict(zip(self.order, self.plan))
        placed, order = set(), []
        while len(order) < len(self.order):
            waiting = [name for name in self.order if name not in placed]
            name = next((n for n in waiting if sources[n] <= placed), waiting[0])
            placed.add(name)
            order.append(entries[name])
        return order

    def refresh(self, inst, out_slots=None) -> None:
        """Read ``inst``'s outputs into the values again (after its state was changed)."""
        if out_slots is None:
            out_slots = next(p[2] for p in self.plan if p[0] is inst)
        values = self.values
        for i, v in zip(out_slots, inst.get_outputs()):
            values[i] = v

    def state(self) -> dict:
        """A snapshot of the run: time, the signals' values and each instance's state
        (``inst.get_state()``); :meth:`restore` goes back to it."""
        return {"time": self.time, "values": list(self.values),
                "instances": {name: inst.get_state() for name, inst in self.instances.items()}}

    def restore(self, state: dict) -> None:
        """Go back to ``state`` (of :meth:`state`; it can be restored again)."""
        for name, inst in self.instances.items():
            inst.set_state(state["instances"][name])
        self.values[:] = state["values"]
        self.time = state["time"]

    def row(self) -> tuple:
        """The recorded signals' present values, in ``system.record`` order."""
        return self._record(self.values)

    def value(self, signal: str) -> float:
        """The present value of a connected or recorded ``signal``."""
        return self.values[self.slots[signal]]

    def _step_members(self) -> None:
        """:meth:`step` of a Gauss-Seidel system at one rate: each member pulls its inputs,
        steps and stores its outputs (:func:`member_calls`)."""
        h, t, values = self.system.step, self.time, self.values
        try:
            for pull, step, read, source, out, inst in self._members:
                if pull is not None:
                    pull(values)
                if step(t, h) is False:
                    raise inst.step_refused(t)
                values[out] = read(source)
        except CoSimulationError:
            raise
        except Exception as exc:  # noqa: BLE001 - as the instance's do_step reports it
            raise CoSimulationError(inst.name, t, str(exc)) from None
        self.time = t + h

    def free_state(self, state: dict) -> None:
        """Release the instances' states in ``state`` (FMU states live in the FMU)."""
        for name, inst in self.instances.items():
            inst.free_state(state["instances"][name])

    def step(self, split: dict | None = None, start: tuple = (0, 0, 0)) -> None:
        """One communication step of every instance from ``time``; ``time`` += h.

        ``split`` (instance name -> n) takes this one step with those instances in n times
        their sub-steps (inputs held), as a master retrying a refused step does.  ``start``
        (group, member, sub-step) takes only the rest of the step from there on, as the
        compiled mode does when a kernel declined a step (Gauss-Seidel).  A refusal raises
        the instance's :class:`fmus.cosim.master.CoSimulationError`."""
        if self._members is not None and not split and start == (0, 0, 0):
            self._step_members()
            return
        h, t, jacobi, values = self.system.step, self.time, self.jacobi, self.values
        groups = self.groups
        if split:
            by_instance = {id(inst): name for name, inst in self.instances.items()}
            groups = rate_groups([(inst, ins, outs, n * split.get(by_instance[id(inst)], 1))
                                  for inst, ins, outs, n in self.plan])
        exchanges_by_group = _exchanges_of(groups) if split else self._exchanges
        held = values[:] if jacobi else values
        first_group, first_member, first_substep = start
        for g, ((substeps, members), exchanges) in enumerate(zip(groups, exchanges_by_group, strict=True)):
            if g < first_group:
                continue
            if g > first_group:
                first_member = first_substep = 0
            if substeps == 1 and first_member == 0:
                inst, gather, outputs = exchanges[0]
                if gather is not None:
                    inst.set_inputs(gather(held))
                inst.do_step(t, h)
                values[outputs] = inst.get_outputs()
                continue
            # Components of one rate step together, exchanging values at every
            # sub-step; what they read from outside the group is held.
            local = held[:] if jacobi else values
            dt = h / substeps
            for j in range(first_substep, substeps):
                start_of_substep = local[:] if jacobi else local
                for inst, in_slots, out_slots in members[first_member if j == first_substep else 0:]:
                    if in_slots:
                        inst.set_inputs([start_of_substep[i] for i in in_slots])
                    inst.do_step(t + j * dt, dt)
                    for i, v in zip(out_slots, inst.get_outputs()):
                        values[i] = v
                        local[i] = v
        # The communication point advances by adding h, as fmpy's and Ecos' masters do:
        # an exported system then runs there on the very same time points.
        self.time = t + h
