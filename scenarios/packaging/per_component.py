"""A scene as one FMU instance per component that tracks in Jacobi masters used plainly.

Ecos, libcosim and fmpy's SSP runner step every instance from the values all held at the
step's start: every connection costs one communication step h.  Our master closes the
bench's chain encoder -> derivator -> controller (and observer) -> drive within one 1 ms
period (Gauss-Seidel); stepped at h = T there, the chain takes three periods and the robot
leaves the circle (docs/ssp.md).  The per-component package therefore steps at a base step
h = T / n and gives every sampled component the sub-step of the period it samples on (its
Integer parameter ``sample_phase``, docs/contract.md):

* the **stage** of a component is the number of sampled connections before it in the
  period (the master's Gauss-Seidel order: a sampled output, ``variability="discrete"``, is
  read in the same period): derivator 0, controller and observers 1, drives 2 on the bench;
  thesis_sim's controller 0;
* the last stage samples at each period's start (phase 0: a supplier's drive that samples
  at its period's start fits in), the earlier ones one sub-step per stage before it:
  ``phase = (stage - last) mod n`` (derivator n - 2, controller and observers n - 1,
  drives 0); each connection then delivers its sample exactly when the next stage takes
  its own.  So no stage that reads the plant samples on the run's first step, where fmpy
  feeds 0.0 to every input; a one-stage chain (thesis_sim's controller) therefore samples
  on sub-step 1; at n = 1 every phase is 0 and those instances get ``hold_first_step``
  (their first sample on the second step, as in every tool);
* n: the Jacobi master adds one sub-step per stage and one into the plant to our
  master's loop, (last + 1) h, and the tracking error grows with that delay (measured:
  thesis_sim_circle e_ef x(1 + 2.03/n), the bench x1.005 at n = 4).  Exporting a scene,
  :func:`choose_substeps_by_trial` runs the package's loop in process as a Jacobi master
  does (what Ecos and libcosim do bit for bit) at the smallest n that holds the stages,
  extrapolates the ratio to our master's e_ef and τ_ef linearly in h, and takes the
  smallest n of :data:`SUBSTEP_CHOICES` it expects within :data:`TRACKING_GOAL`, checked by
  a run (the next one when it is not); a system without a scene takes the smallest n that
  holds the stages.  Only the part of the deviation the delay makes shrinks with h: a
  scene whose own metrics are not reproducible to the goal (our master's run moved by a
  1 nm shift of the plant's start, :func:`reproducibility`, measured when the first n
  misses) is matched to the goal beyond that floor; chasing the rest, which is not a
  function of h, took bench_triangle_PDMDx to n = 500 (docs/ssp.md).

The package states the base step where the tools read it (libcosim's
``osp:FixedStepAlgorithm baseStepSize``, parcosim's step annotation; Ecos and fmpy take it
as an argument: docs/ssp.md), bakes every instance's parameters into its FMU copy (fmpy
ignores bindings) and binds them in the SSD (libcosim, Ecos' ``init(t, "parameters")``).

``internal_observer``: the drives estimate their current themselves (``DCMotorDrive``'s
``internal_observer``, the observer of 7.20 inside the drive FMU, as a real drive closes
its current loop): the observers ``obs1``/``obs2`` and their connections go, which takes
the one connection inside the 1 ms current loop out of the Jacobi master.  At n = 1 the
chain still costs 2 periods on the position and 3 on the velocity feedback, at the stability
limit of the task-space PD laws (``benchmarks/jacobi_delay_margin.py``): the position
controller gets them as its :data:`COMPENSATION` (:func:`feedback_delays`) and its law
predicts over them (docs/ssp.md "Delay compensation").  A ``substeps`` given for a scene is
checked by a run (:func:`check_tracking`, a :class:`TrackingWarning` by name outside
:data:`TRACKING_BOUND`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

from fmus.cosim.system import Component, System, split_signal

from scenarios.scenes.scene import Scene

#: The Integer parameter of our sampled FMUs: the sub-step of each period they sample on.
PHASE = "sample_phase"
#: The Boolean parameter of our sampled FMUs: the run's first step does not sample.
HOLD_FIRST = "hold_first_step"
#: Sub-steps per period the export chooses from: T / n a whole number of nanoseconds for
#: T = 1 ms (libcosim's time unit), smallest first.
SUBSTEP_CHOICES = (1, 2, 4, 5, 8, 10, 20, 25, 40, 50, 100, 125, 200, 250, 500, 1000)
#: The package's e_ef and τ_ef within this factor of our master's (issue 26's goal: x1.01).
TRACKING_GOAL = 0.01
#: The bound a package exported at a given ``substeps`` is checked against (issue 26's must: x1.05).
TRACKING_BOUND = 0.05
#: How far :func:`reproducibility` moves the plant's start [m]: far below an encoder count.
START_SHIFT = 1e-9
#: The observer model whose instances ``internal_observer`` folds into their drives.
OBSERVER_MODEL = "CurrentObserver"
#: The Integer parameters of the position controller: periods of delay of its angles and of
#: its rates before its commands take effect, which its law predicts over (docs/contract.md).
COMPENSATION = ("delay_compensation", "velocity_delay_compensation")


@dataclass(frozen=True)
class Timing:
    """The per-component package's timing of one system.

    ``substeps`` n = period / ``base_step``; ``stages`` and ``phases`` by instance
    (``phases``: the instances that take a ``sample_phase``).
    """

    period: float
    substeps: int
    stages: dict
    phases: dict

    @property
    def base_step(self) -> float:
        return self.period / self.substeps


def stages(system: System, discrete: dict) -> dict:
    """Instance -> the number of sampled connections before it in a period: the longest
    chain of connections from a sampled output (``discrete``: instance -> the names of its
    outputs of ``variability="discrete"``).

    Raises
    ------
    ValueError
        Sampled outputs that form a loop (no period can hold it).
    """
    names = [c.name for c in system.components]
    edges = set()
    for conn in system.connections:
        src, out = split_signal(conn.source)
        dst, _ = split_signal(conn.target)
        if src != dst and out in discrete.get(src, ()):
            edges.add((src, dst))
    stage = dict.fromkeys(names, 0)
    for _ in range(len(names) + 1):
        changed = False
        for src, dst in edges:
            if stage[dst] < stage[src] + 1:
                stage[dst], changed = stage[src] + 1, True
        if not changed:
            return stage
    loop = sorted({f"{s} -> {d}" for s, d in edges if stage[d] > len(names)})
    raise ValueError(f"sampled outputs form a loop ({', '.join(loop) or 'among ' + ', '.join(names)}): "
                     "no sample phase can order it")


def choose_substeps(last_stage: int, substeps: int | None = None) -> int:
    """The smallest n of :data:`SUBSTEP_CHOICES` that holds ``last_stage + 1`` stages in a
    period, or ``substeps`` checked (any n >= 1: with fewer sub-steps than stages the chain
    spans more periods, e.g. n = 1, every sample at the period start, is the plain package
    at the period)."""
    if substeps is not None:
        if isinstance(substeps, bool) or int(substeps) != substeps or substeps < 1:
            raise ValueError(f"substeps = {substeps!r} must be a whole number >= 1")
        return int(substeps)   # below last_stage + 1 the chain spans more than one period
    for n in SUBSTEP_CHOICES:
        if n >= last_stage + 1:
            return n
    raise ValueError(f"a chain of {last_stage + 1} sampled stages needs more than {SUBSTEP_CHOICES[-1]} sub-steps")


def component_timing(system: System, variables: dict, substeps: int | None = None) -> Timing:
    """The base step and phases of ``system`` (module docstring).

    ``variables``: instance -> {name: variable with ``causality`` and ``variability``} (the
    FMUs' model descriptions).  Only instances whose FMU has :data:`PHASE` get a phase; the
    last stage is the highest of them (a foreign FMU that reads a sample counts too: it is
    taken to sample at its period's start).
    """
    stage = stages(system, {n: {v for v, var in vs.items() if var.causality == "output"
                                and var.variability == "discrete"} for n, vs in variables.items()})
    adjustable = [n for n in stage if PHASE in variables[n]]
    for name in adjustable:
        T = system.component(name).parameters.get("T", system.step)
        if abs(T - system.step) > 1e-12 * system.step:
            raise ValueError(f"{name}.T = {T!r} s: the per-component package samples every component at the "
                             f"scene's period {system.step!r} s")
    samplers = adjustable + [c.name for c in system.components
                             if c.name not in adjustable and _foreign(c.model) and stage[c.name] > 0]
    last = max((stage[n] for n in samplers), default=0)
    n = choose_substeps(last, substeps)
    # A one-stage chain (thesis_sim's controller reads the plant directly) samples on the
    # period's second sub-step: fmpy feeds 0.0 to every input on the run's first step.
    shift = 1 if last == 0 and n >= 2 else 0
    return Timing(system.step, n, stage, {name: (stage[name] - last + shift) % n for name in adjustable})


def _tracking(scene: Scene, result, every: int) -> tuple:
    """(e_ef, τ_ef) of a run of ``scene``'s components, at every ``every``-th row."""
    from scenarios.run.metrics import scene_metrics

    columns = {name: result[signal][::every] for name, signal in scene.columns.items()
               if name in ("x", "y", "x_d", "y_d", "tau1", "tau2")}
    columns["t"] = result.time[::every]
    m = scene_metrics(scene, columns, 1.0, result.completed)
    return m["e_ef_mm"], m["tau_ef_Nm"]


def reproducibility(scene: Scene, shift: float = START_SHIFT) -> float:
    """How far ``scene``'s e_ef and τ_ef move in our master when the plant starts ``shift``
    m away along x (its parameter ``x0`` ± ``shift``): the largest |ratio - 1|; 0.0 when
    no component has an ``x0``.  A nanometre is far below an encoder count: a scene whose
    metrics move by more than the goal under it cannot be matched to the goal by any step
    (``bench_triangle_PDMDx``: τ_ef by up to 0.6 %, docs/ssp.md)."""
    from fmus.cosim.master import simulate

    plant = next((c for c in scene.system.components if "x0" in c.parameters), None)
    if plant is None:
        return 0.0
    e_ours, tau_ours = _tracking(scene, simulate(scene.system, mode="inprocess"), 1)
    moved = []
    for sign in (1.0, -1.0):
        shifted = dataclasses.replace(plant, parameters={**plant.parameters, "x0": plant.parameters["x0"] + sign * shift})
        system = dataclasses.replace(scene.system, components=tuple(
            shifted if c.name == plant.name else c for c in scene.system.components))
        e, tau = _tracking(dataclasses.replace(scene, system=system), simulate(system, mode="inprocess"), 1)
        moved += [abs(e / e_ours - 1.0), abs(tau / tau_ours - 1.0)]
    return max(moved)


def next_substeps(n: int, deviation: float, goal: float, floor: float = 0.0) -> int | None:
    """The trial's rule: None when a deviation of the package's e_ef or τ_ef from our
    master's at ``n`` sub-steps is within ``goal`` plus the scene's own ``floor``
    (:func:`reproducibility`), else the next n of :data:`SUBSTEP_CHOICES` to try: the part
    of the deviation above the floor grows with the added delay, (last stage + 1) h, so n
    is scaled to bring it to ``goal``.

    Raises
    ------
    ValueError
        No larger n to try.
    """
    if deviation <= goal + floor:
        return None
    wanted = n * (deviation - floor) / goal if deviation == deviation else 0.0
    larger = [c for c in SUBSTEP_CHOICES if c > n]
    if not larger:
        raise ValueError(f"no base step of {SUBSTEP_CHOICES} sub-steps brings the deviation {deviation:.4g} "
                         f"within {goal:g} (+ the scene's own {floor:.2g})")
    return next((c for c in larger if c >= wanted), larger[-1])


def choose_substeps_by_trial(scene: Scene, system: System, variables: dict, goal: float = TRACKING_GOAL) -> tuple:
    """(n, {n tried: (e_ef ratio, τ_ef ratio)}, floor): the sub-steps that bring ``system``
    (the scene's components, as exported) run as a Jacobi master runs it within ``goal`` of
    our master's e_ef and τ_ef on ``scene`` (module docstring), beyond ``floor``, the
    scene's own :func:`reproducibility` (measured only when the first n misses the goal;
    else 0.0).

    Raises
    ------
    ValueError
        No n of :data:`SUBSTEP_CHOICES` reaches it, or our own run gives no finite, positive
        e_ef and τ_ef to compare with (pass ``substeps``).
    """
    from fmus.cosim.master import simulate

    ours = _tracking(scene, simulate(scene.system, mode="inprocess"), 1)
    if not all(math.isfinite(m) and m > 0.0 for m in ours):   # no n can be measured against it: refuse now
        raise ValueError(f"scene {scene.name}: our master's own run gives e_ef = {ours[0]!r}, tau_ef = {ours[1]!r}: "
                         "no sub-step count can be chosen against it; pass substeps")
    tried = {}
    floor = 0.0
    n = component_timing(system, variables).substeps
    while True:
        tried[n] = jacobi_ratios(scene, system, variables, n, ours)
        deviation = max(abs(r - 1.0) for r in tried[n])
        if len(tried) == 1 and deviation > goal:
            floor = reproducibility(scene)
        try:
            following = next_substeps(n, deviation, goal, floor)
        except ValueError as exc:
            raise ValueError(f"scene {scene.name}: {exc} (tried n: ratios {tried}); pass substeps") from None
        if following is None:
            return n, tried, floor
        n = following


def jacobi_ratios(scene: Scene, system: System, variables: dict, n: int, ours: tuple | None = None) -> tuple:
    """(e_ef ratio, τ_ef ratio) of ``system`` (``scene``'s components as exported) stepped as
    its package at ``n`` sub-steps in a Jacobi master (in process: what Ecos and libcosim
    give bit for bit) against our master's ``ours`` = (e_ef, τ_ef), run when None."""
    from fmus.cosim.master import simulate

    if ours is None:
        ours = _tracking(scene, simulate(scene.system, mode="inprocess"), 1)
    stepped, _ = per_component_system(system, variables, n)
    e, tau = _tracking(scene, simulate(stepped, mode="inprocess", coupling="jacobi"), n)
    return e / ours[0], tau / ours[1]


class TrackingWarning(UserWarning):
    """A per-component package exported at a given ``substeps`` that does not track its scene."""


def check_tracking(scene: Scene, system: System, variables: dict, n: int, bound: float = TRACKING_BOUND) -> tuple:
    """The :func:`jacobi_ratios` of the package at ``n``; a :class:`TrackingWarning` naming
    the scene, its controller's strategy, n and both ratios when one is off ours by more
    than ``bound`` (issue 26's must: 5 %).  At n below the chain's stages + 1 every
    connection costs a whole period: at 1 ms the bench's chain adds 2 periods to the
    position and 3 to the velocity feedback, which the task-space PD laws (lam = 70/s,
    m* = 0.207 kg above the task-space inertia's 0.128 kg) do not survive unless the
    controller compensates them (:data:`COMPENSATION`; a replacement controller without
    the parameters; docs/ssp.md)."""
    ratios = jacobi_ratios(scene, system, variables, n)
    if max(abs(r - 1.0) for r in ratios) > bound:
        import warnings

        strategy = next((c.parameters["strategy"] for c in system.components if "strategy" in c.parameters), None)
        named = f"scene {scene.name}" + (f" (strategy {strategy})" if strategy else "")
        warnings.warn(f"{named}: its per-component package at {n} sub-step(s) per period (h = "
                      f"{system.step / n:g} s) does not track in a Jacobi master: e_ef x{ratios[0]:.3f}, "
                      f"tau_ef x{ratios[1]:.3f} of parcosim run's (bound x{1 + bound:g}); export without "
                      "--substeps to get the base step the export's trial chooses", TrackingWarning, stacklevel=3)
    return ratios


def _foreign(model: str) -> bool:
    return str(model).lower().endswith(".fmu")


def with_internal_observers(system: System) -> System:
    """``system`` with each :data:`OBSERVER_MODEL` instance folded into the drive it feeds
    (``<obs>.i_hat -> <drive>.i_hat``): the drive gets ``internal_observer = True`` (and the
    observer's ``kind`` as ``observer_kind``); the observer and its connections go.

    Raises
    ------
    ValueError
        An observer that feeds no drive's ``i_hat``, one whose motor preset differs from
        its drive's, or one that sets other parameters (the drive's own observer uses the
        drive's motor).
    """
    observers = {c.name: c for c in system.components if c.model == OBSERVER_MODEL}
    if not observers:
        return system
    fed = {}
    for conn in system.connections:
        src, out = split_signal(conn.source)
        dst, inp = split_signal(conn.target)
        if src in observers and out == "i_hat" and inp == "i_hat":
            fed[src] = dst
    components = []
    for c in system.components:
        if c.name in observers:
            if c.name not in fed:
                raise ValueError(f"observer {c.name} feeds no drive's i_hat: it cannot move into a drive")
            continue
        mine = [o for o, d in fed.items() if d == c.name]
        if mine:
            obs = observers[mine[0]]
            preset = obs.parameters.get("preset", "motor1")
            if preset != c.parameters.get("preset", "motor1"):
                raise ValueError(f"observer {obs.name} (preset {preset!r}) and drive {c.name} "
                                 f"(preset {c.parameters.get('preset', 'motor1')!r}): an internal observer "
                                 "uses its drive's motor")
            other = sorted(set(obs.parameters) - {"preset", "kind"})
            if other:
                raise ValueError(f"observer {obs.name} sets {', '.join(other)}: an internal observer takes its "
                                 "drive's motor and only the parameter kind (as observer_kind)")
            extra = {"observer_kind": obs.parameters["kind"]} if "kind" in obs.parameters else {}
            c = dataclasses.replace(c, parameters={**c.parameters, "internal_observer": True, **extra})
        components.append(c)
    keep = [conn for conn in system.connections
            if split_signal(conn.source)[0] not in observers and split_signal(conn.target)[0] not in observers]
    record = tuple(s for s in system.record if split_signal(s)[0] not in observers)
    return dataclasses.replace(system, components=tuple(components), connections=tuple(keep), record=record)


def _hops(system: System, start: str) -> dict:
    """Instance -> the fewest connections from ``start`` to it (``start``: 0)."""
    edges = {}
    for conn in system.connections:
        src, dst = split_signal(conn.source)[0], split_signal(conn.target)[0]
        if src != dst:
            edges.setdefault(src, set()).add(dst)
    hops, frontier = {start: 0}, [start]
    while frontier:
        following = []
        for name in frontier:
            for dst in sorted(edges.get(name, ())):
                if dst not in hops:
                    hops[dst] = hops[name] + 1
                    following.append(dst)
        frontier = following
    return hops


def feedback_delays(system: System, name: str) -> tuple:
    """(angles, rates): the periods by which a Jacobi master stepping ``system`` at its period
    (n = 1: each connection costs a step) delays instance ``name``'s inputs ``q1`` and ``dq1``
    before the commands it computes from them take effect, against our master's loop: the
    connections from ``name`` back to the instance its angles come from (ctrl -> drive ->
    plant: 2), and for the rates those from that instance to the one they come from
    (plant -> deriv: 1 more).  (0, 0) when an input is not connected or no path closes."""
    source = {split_signal(c.target)[1]: split_signal(c.source)[0] for c in system.connections
              if split_signal(c.target)[0] == name}
    if "q1" not in source or "dq1" not in source:
        return 0, 0
    angles = _hops(system, name).get(source["q1"])
    rates = _hops(system, source["q1"]).get(source["dq1"])
    if angles is None or rates is None:
        return 0, 0
    return angles, angles + rates


def per_component_system(system: System, variables: dict, substeps: int | None = None) -> tuple:
    """(``system`` stepped at its package's base step with each sampled component's
    :data:`PHASE`, its :class:`Timing`).  A phase of 0 (the default) is not set, so a
    replacement FMU without the parameter takes the same bindings.  An instance that samples
    on the run's first step (phase 0: every one at n = 1) and has :data:`HOLD_FIRST` gets it
    true: fmpy's runner feeds 0.0 to every input on that step, which the sample would take as
    the plant's angles and the reference (module docstring).  At n = 1 an instance with
    :data:`COMPENSATION` gets its :func:`feedback_delays`, which its law predicts over."""
    if any(c.substeps != 1 for c in system.components):
        raise ValueError("multi-rate components (substeps > 1) cannot be exported per component")
    timing = component_timing(system, variables, substeps)

    def timed(c):
        if c.name not in timing.phases:
            return c
        phase = timing.phases[c.name]
        extra = {PHASE: phase} if phase else ({HOLD_FIRST: True} if HOLD_FIRST in variables[c.name] else {})
        if timing.substeps == 1 and all(p in variables[c.name] for p in COMPENSATION):
            delays = feedback_delays(system, c.name)
            extra.update({p: d for p, d in zip(COMPENSATION, delays) if d})
        return dataclasses.replace(c, parameters={**c.parameters, **extra}) if extra else c

    components = tuple(timed(c) for c in system.components)
    return dataclasses.replace(system, components=components, step=timing.base_step), timing


def _variables(system: System, fmu_dir=None) -> tuple:
    """(``system`` with its FMU-file components named, {model: FMU file} of those, instance ->
    its FMU's variables)."""
    from fmus.cosim.foreign import named_models
    from fmus.ssp.export import _fmu_paths, _read_variables

    named, fmus = named_models(system)
    paths = _fmu_paths([c.model for c in named.components if c.model not in fmus], fmu_dir)
    paths.update({model: Path(f) for model, f in fmus.items()})
    return named, fmus, {c.name: _read_variables(c.model, paths[c.model]) for c in named.components}


def trial(scene: Scene, internal_observer: bool = False, goal: float = TRACKING_GOAL, fmu_dir=None) -> tuple:
    """:func:`choose_substeps_by_trial` of the package ``export_per_component(scene, ...,
    internal_observer=internal_observer)`` writes: (n, {n: ratios}, floor)."""
    system = with_internal_observers(scene.system) if internal_observer else scene.system
    return choose_substeps_by_trial(scene, system, _variables(system, fmu_dir)[2], goal)


def export_per_component(scene: Scene | System, path, fmu_dir=None, substeps: int | None = None,
                         internal_observer: bool = False, goal: float = TRACKING_GOAL, native: bool = False) -> Path:
    """Write ``scene`` (or a system) as a per-component SSP package for Jacobi masters
    (module docstring) to ``path`` and return its path (``parcosim export-ssp SCENE PATH
    --per-component [--substeps N] [--internal-observer] [--native]``).

    ``substeps`` None: chosen by :func:`choose_substeps_by_trial` for a scene (``goal``),
    the smallest that holds the stages for a system; given for a scene, the package is run
    in process as a Jacobi master runs it and a :class:`TrackingWarning` names the scene
    when it misses :data:`TRACKING_BOUND` (:func:`check_tracking`: a plain 1 ms package of
    a task-space PD scene oscillates).  Components that name an FMU file
    (``--replace``) go into the package as they are; parameters their FMU lacks are left
    out with a warning (:func:`fmus.cosim.foreign.named_models`).

    ``native``: the same package (instances, base step, phases, bindings) whose instances
    are native FMUs (docs/native.md), each built with its instance's parameters, phase
    included, as its compiled start values (``<fmu_dir>/native``, default
    ``fmus/build/native``; :func:`fmus.native.run.native_instances`).  A component of a
    model with no native FMU (SpecPlant) refuses the export by name before anything is built.
    """
    from fmus.ssp.export import export_ssp

    system = scene.system if isinstance(scene, Scene) else scene
    if native:
        from fmus.native.run import refuse_without_native

        name = scene.name if isinstance(scene, Scene) else "system"
        refuse_without_native(system, f"{name}: export-ssp --per-component --native")
    if internal_observer:
        system = with_internal_observers(system)
    named, fmus, variables = _variables(system, fmu_dir)
    if substeps is None and isinstance(scene, Scene):
        substeps = choose_substeps_by_trial(scene, system, variables, goal)[0]
    elif isinstance(scene, Scene):
        check_tracking(scene, system, variables, choose_substeps(0, substeps))
    stepped, _ = per_component_system(named, variables, substeps)
    if not native:
        return export_ssp(stepped, path, fmu_dir, fmus=fmus)
    from fmus.native.build import DEFAULT_NATIVE_OUT
    from fmus.native.run import native_instances

    given = {c.name for c in system.components if _foreign(c.model)}   # --replace: as they are
    ours = dataclasses.replace(stepped, components=tuple(c for c in stepped.components if c.name not in given))
    own = native_instances(ours, Path(fmu_dir) / "native" if fmu_dir else DEFAULT_NATIVE_OUT)
    first = {}
    for instance, fmu in own.items():
        first.setdefault(stepped.component(instance).model, fmu)
    return export_ssp(stepped, path, fmu_dir, fmus={**first, **fmus}, instance_fmus=own)
