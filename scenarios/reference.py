"""A monolithic reference run of a scene: the truth a co-simulation is measured against.

The co-simulation couples the plant and the drives explicitly at the 1 ms communication
step: each drive advances its current with the shaft speed of the step's start held and
hands the plant the torque of the step's END, which the plant holds over the whole step.
The reference removes that coupling error and the plant's fixed-step error, and nothing
else:

* the **continuous part** — the plant's state ``[q, dq]`` (7.12, forward dynamics 5.66 with
  its Baumgarte term, :meth:`plant.PlantSimulator.derivative`) and the armature current of
  every drive, ``L di/dt = v - R i - ke omega`` (4.162) with omega the plant's actuated
  joint rate — is ONE ODE, :meth:`plant.actuated.ActuatedPlant.derivative` (the same model
  code as the ``ActuatedFiveBarPlant`` FMU), integrated by ``scipy.integrate.solve_ivp``
  (DOP853, rtol 1e-10 by default) over each sample interval, restarted at every sample; the
  shaft torque is that of the instantaneous current and speed (B.2);
* a drive's **LuGre friction** (``friction="lugre"``) stays discrete, as in the drive's own
  step: its bristles advance over the interval with the joint speed of the sample held and
  their mean torque is held on the joint (:meth:`plant.actuated.ActuatedPlant.held_friction`);
  the drive's ``tau`` output is :meth:`motor.Drive.torque` of the state at the interval's end;
* the **discrete part** — trajectory, derivator, position controller, observers — are the
  scene's own components, the master's in-process instances, initialised and stepped by the
  master's own loop (:class:`fmus.cosim.stepper.Stepper`, the Gauss-Seidel order of
  :func:`fmus.cosim.master.stepping_order`) with the same inputs as in the co-simulation;
* each drive samples its voltage with its own :meth:`motor.Drive.sample_voltage` at t_k, at
  the drive's place in that order — the co-simulation drive's current controller, PWM
  quantisation, current noise and offset — held over [t_k, t_k+1] (zero-order hold); the
  drive's ``v`` output is then that voltage, so the observers read the previous interval's
  voltage, as in the co-simulation.

So the reference models exactly what the co-simulation models but for the plant/drive
coupling at the communication step.

Encoder quantisation is the plant's own (:meth:`plant.PlantSimulator.outputs`, applied
to the integrated state at each sample).

So, per sample t_k (order ``deriv, ctrl, traj, obs1, obs2, drive1, drive2, plant`` for
the bench): derivator and controller read the plant at t_k, the trajectory moves to
t_k+1, the observers read the voltage over [t_k-1, t_k] and the derivator's speed at
t_k, the drives sample their voltages, and the continuous part is integrated to t_k+1.

``coupling`` selects what replaces the plant/drive coupling (the discrete part is the
same in all four):

``"monolithic"`` (the reference)
    as above.
``"held_speed"``
    a diagnostic: as ``"monolithic"``, but each drive sees the shaft speed of the
    sample instant t_k over the whole interval (back-emf, viscous and Coulomb terms),
    as the co-simulation's drive does; the torque still follows the current
    continuously.  Against ``"monolithic"`` it measures the effect of the held speed,
    against ``"cosim"`` that of the end-of-step torque being held.
``"cosim"``
    the co-simulation's own explicit coupling: the drive slaves are stepped as the
    master steps them and only the plant is integrated by solve_ivp, with the drives'
    end-of-step torques held.  It differs from the master's run only by the plant's
    integration error, so comparing the two isolates that error, and comparing it
    with ``"monolithic"`` isolates the coupling error.
``"mean"``
    a what-if: as ``"cosim"``, but the plant holds each drive's MEAN shaft torque over
    the step, kt * mean(i) - b omega - mu tanh(omega/omega_eps) with omega held at the
    step start (mean(i) from the exact solution of 4.162 for the held voltage and
    speed); a LuGre drive's own mean torque (``torque_output="mean"``).  It measures what a drive output "torque averaged over the step" would
    buy the co-simulation.

Scenes: any :class:`fmus.cosim.system.System` with one ``FiveBarPlant``, up to two
``DCMotorDrive`` (each connected ``drive.tau -> plant.tau<j>`` and reading
``plant.dq<j>`` as ``omega``, L > 0, sample time T equal to the communication step),
and discrete components; e.g. every ``bench_*`` scene and ``thesis_sim_circle`` (ideal
actuators: no drives, the controller's torques held on the plant).  See
``docs/reference.md`` for its convergence and the co-simulation's measured deviation.
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.integrate import solve_ivp

from fmus.cosim.backends import CoSimulationError, InProcessInstance
from fmus.cosim.master import RecordedRun, stepping_order
from fmus.slave.declarations import publish_plant
from fmus.cosim.stepper import Stepper
from fmus.cosim.system import System
from motor import shaft_torque
from plant import fivebar
from plant.actuated import ActuatedPlant

COUPLINGS = ("monolithic", "held_speed", "cosim", "mean")
#: Default tolerances: convergence measured in docs/reference.md.
RTOL = 1e-10
ATOL = 1e-13
METHOD = "DOP853"


class ReferenceError(RuntimeError):
    """The reference cannot run this system, or a component refused a step."""


@dataclass
class ReferenceResult(RecordedRun):
    """A reference run on the communication grid, laid out as :class:`fmus.cosim.master.Result`.

    ``signals`` has every output of every component ("instance.variable"); row 0 is the
    state after initialisation, row k the state after the k-th sample interval (a
    continuous output at t_k, a sampled output the sample held over [t_k-1, t_k]), as in
    the master's record.  ``columns`` (when run from a scene): ``t`` and the scene's
    columns (``x, y, x_d, y_d, tau1, tau2`` and, on the bench, ``i1, i2`` ...).
    """

    time: np.ndarray
    signals: dict
    columns: dict
    order: tuple
    coupling: str
    method: str
    rtol: float
    atol: float
    wall_s: float
    nfev: int = 0
    steps: int = 0
    error: str | None = None
    extra: dict = field(default_factory=dict)


# --- the scene's components, stepped by the master's own Gauss-Seidel loop ----------------

def _real_outputs(instance) -> list:
    return [v.name for v in instance.variables.values() if v.type == "Real" and v.causality == "output"]


class _Replaced:
    """An instance of the master's loop (:class:`fmus.cosim.stepper.Stepper`) whose ``do_step`` the
    reference replaces; everything else (variables, inputs, outputs, initialisation) is the
    in-process instance's."""

    def __init__(self, inner):
        self.inner = inner
        self.slave = inner.slave

    def __getattr__(self, name):
        return getattr(self.inner, name)


class _SampledDrive(_Replaced):
    """A drive of the monolithic block: at t_k it only samples its voltage with its own
    :meth:`motor.Drive.sample_voltage` (the co-simulation drive's controller, PWM and current
    noise), held over the interval; its current is the continuous block's."""

    link = None     # its _DriveLink, once the instances are initialised

    def do_step(self, t: float, h: float) -> None:
        slave = self.slave
        try:
            v = slave.drive.sample_voltage(slave.i_ref, slave.v_ref, slave.i_hat, h)
        except ValueError as exc:
            raise ReferenceError(f"{self.inner.name} refused the step from t = {t:.6g} s: {exc}") from None
        self.link.v = slave.v = v


class _MeanTorqueDrive(_Replaced):
    """A drive stepped as in the co-simulation that also gives its mean torque over the step
    (the ``"mean"`` what-if)."""

    link = None     # its _DriveLink, once the instances are initialised

    def do_step(self, t: float, h: float) -> None:
        slave = self.slave
        i_start, omega = slave.drive.i, slave.omega
        self.inner.do_step(t, h)
        if slave.drive.lugre is None:
            self.link.tau_mean = _mean_torque(slave, i_start, slave.v, omega, h)
        elif slave.drive.torque_output == "mean":     # the drive's own mean, its LuGre bristles' included
            self.link.tau_mean = slave.tau
        else:
            raise ReferenceError(f"drive {self.inner.name}: the 'mean' what-if of a LuGre drive needs "
                                 "torque_output = 'mean' (its own mean torque)")


class _IntegratedPlant(_Replaced):
    """The plant whose interval is the continuous block integrated by solve_ivp; with the
    monolithic coupling the drives' currents and bristles advance with it and their outputs
    (``i``, ``tau``) are set at the interval's end, in the loop's values too."""

    def __init__(self, inner, coupling, solver):
        super().__init__(inner)
        self.coupling, self.solver = coupling, solver
        self.block, self.links, self.values, self.slots = None, [], None, {}   # set by couple
        self.nfev = self.steps = 0
        self.first_step = None

    def couple(self, block, links, stepper) -> None:
        """The continuous block, the drives coupled to the plant and the loop whose values
        get the drives' outputs (once the instances are initialised)."""
        self.block, self.links, self.values, self.slots = block, links, stepper.values, stepper.slots

    def do_step(self, t: float, h: float) -> None:
        sim, slave, block = self.slave.sim, self.slave, self.block
        monolithic = self.coupling in ("monolithic", "held_speed")
        drives = [link.slave.drive for link in self.links] if monolithic else []
        omega = fivebar.world_rates(sim.y[7:])
        for link in self.links:
            link.omega_held = omega[link.joint]
        block.held = [slave.tau1, slave.tau2]
        if self.coupling == "mean":
            for link in self.links:
                block.held[link.joint] = link.tau_mean
        bristles = block.hold_friction(h) if monolithic else []
        z0 = np.concatenate([sim.y, [d.i for d in drives]])
        method, rtol, atol = self.solver
        sol = solve_ivp(block.rhs, (t, t + h), z0, method=method, rtol=rtol, atol=atol, first_step=self.first_step)
        if sol.status != 0 or not np.all(np.isfinite(sol.y[:, -1])):
            raise ReferenceError(f"{self.inner.name}: solve_ivp failed over [{t:.6g}, {t + h:.6g}] s: {sol.message}")
        self.nfev += sol.nfev
        self.steps += len(sol.t) - 1
        if len(sol.t) > 2:
            self.first_step = float(sol.t[-2] - sol.t[-3]) if len(sol.t) > 3 else float(sol.t[-2] - t)
        z = sol.y[:, -1]
        sim.y = z[:14].copy()
        sim.time = t + h
        publish_plant(slave, sim)
        if monolithic:
            self._drives_at_the_end(z[14:], bristles)

    def _drives_at_the_end(self, currents, bristles) -> None:
        """Each drive's current and bristles at the interval's end, and its outputs ``i`` and
        ``tau`` (:meth:`motor.Drive.torque`: B.2 or LuGre) from them."""
        omega = fivebar.world_rates(self.slave.sim.y[7:])
        for link, i, bristle in zip(self.links, currents, bristles):
            drive = link.slave.drive
            drive.i = float(i)
            if bristle is not None:
                drive.z = bristle
            w = link.omega_held if self.block.held_speed else omega[link.joint]
            link.slave.i, link.slave.tau = drive.i, drive.torque(w)
            for name in ("i", "tau"):
                slot = self.slots.get(f"{link.name}.{name}")
                if slot is not None:
                    self.values[slot] = getattr(link.slave, name)


# --- the continuous part --------------------------------------------------------------------

@dataclass
class _DriveLink:
    """One drive of the monolithic block: which plant input it drives, its model and voltage."""

    name: str
    joint: int          # 0 for plant.tau1/dq1, 1 for plant.tau2/dq2
    slave: object
    v: float = 0.0          # voltage held over the interval ("monolithic")
    tau_mean: float = 0.0   # mean shaft torque over the interval ("mean")
    omega_held: float = 0.0  # speed at the sample instant ("held_speed")


class _Continuous:
    """Plant state [q(7), dq(7)] and the drives' currents, one ODE: the
    :class:`plant.actuated.ActuatedPlant` of the plant and the drives' models."""

    def __init__(self, sim, drives, held_speed=False):
        self.drives = drives
        self.actuated = ActuatedPlant(sim, [(d.joint + 1, d.slave.drive) for d in drives])
        self.held_speed = held_speed
        self.held = [0.0, 0.0]          # the plant's inputs tau1, tau2 at the sample
        self.friction = [0.0, 0.0]      # the LuGre drives' mean bristle torques over the interval

    def hold_friction(self, h: float) -> list:
        """The LuGre drives' bristles over the next interval, the joint speed held
        (:meth:`plant.actuated.ActuatedPlant.held_friction`, as the drive's own step): their
        mean torque is held on the driven joints; returns each drive's deflection at the
        interval's end (None without LuGre)."""
        self.friction, bristles = self.actuated.held_friction(h)
        return bristles

    def rhs(self, t, z):
        external = list(self.held)
        for d in self.drives:           # a driven joint gets its drive's torque instead
            external[d.joint] = self.friction[d.joint]
        return self.actuated.derivative(z, [d.v for d in self.drives], external,
                                        [d.omega_held for d in self.drives] if self.held_speed else None)


def _mean_torque(drive_slave, i_start, v, omega, h):
    """Shaft torque averaged over a step with v and omega held (exact solution of 4.162)."""
    p = drive_slave.drive.params
    i_inf = (v - p.ke * omega) / p.R
    x = p.R * h / p.L
    i_mean = i_inf + (i_start - i_inf) * (-math.expm1(-x)) / x
    return shaft_torque(i_mean, omega, p)


# --- the run ------------------------------------------------------------------------------

def _system_of(scene_or_name, stop_time, system_changes):
    from scenarios.scenes.catalogue import get_scene
    from scenarios.scenes.scene import Scene

    scene = get_scene(scene_or_name) if isinstance(scene_or_name, str) else scene_or_name
    system = scene.system if isinstance(scene, Scene) else scene
    if not isinstance(system, System):
        raise TypeError(f"expected a scene name, a Scene or a System, got {type(scene_or_name).__name__}")
    if stop_time is not None:
        system = replace(system, stop_time=float(stop_time))
    if system_changes is not None:
        system = system_changes(system)
    return scene, system


def _the_plant(system) -> str:
    plants = [c.name for c in system.components if c.model == "FiveBarPlant"]
    if len(plants) != 1:
        actuated = [c.name for c in system.components if c.model == "ActuatedFiveBarPlant"]
        hint = (f" ({', '.join(actuated)} is an ActuatedFiveBarPlant: its truth is the reference of the scene "
                "before scenarios.scenes.transforms.drives_in_plant)") if actuated else ""
        raise ReferenceError(f"the reference needs exactly one FiveBarPlant, found {len(plants)}{hint}")
    return plants[0]


def _instances(system) -> dict:
    instances = {}
    for c in system.components:
        try:
            instances[c.name] = InProcessInstance(c.model, c.name)
        except ValueError as exc:
            raise ReferenceError(str(exc)) from None
        for name in c.parameters:
            if name not in instances[c.name].variables:
                raise ReferenceError(f"component {c.name}: {c.model} has no parameter {name!r}")
    return instances


def _driving(system, plant_name) -> dict:
    """Drive instance -> the plant joint it drives (:func:`scenarios.scenes.transforms.drive_joints`)."""
    from scenarios.scenes.transforms import drive_joints

    try:
        return drive_joints(system, plant_name)
    except ValueError as exc:
        raise ReferenceError(str(exc)) from None


def _links(system, instances, order, plant_name, coupling) -> dict:
    """The drives that feed the plant, checked: their period is the step, they have an
    electrical state and, but in ``"cosim"``, step before the plant."""
    links, h = {}, system.step
    for name, joint in _driving(system, plant_name).items():
        drive = instances[name].slave.drive
        if abs(drive.T - h) > 1e-12 * h:
            raise ReferenceError(f"drive {name}: controller period T = {drive.T} s differs from the step {h} s")
        if drive.params.L <= 0.0:
            raise ReferenceError(f"drive {name}: L = 0 has no electrical state to integrate")
        if coupling != "cosim" and order.index(name) > order.index(plant_name):
            raise ReferenceError(f"drive {name} steps after the plant: its voltage would not be known")
        links[name] = _DriveLink(name, joint - 1, instances[name].slave, v=drive.v)
    return links


def reference_run(scene_or_name, rtol: float = RTOL, atol: float = ATOL, stop_time: float | None = None,
                  method: str = METHOD, coupling: str = "monolithic", system_changes=None,
                  progress=None) -> ReferenceResult:
    """Run the reference of a scene (a name, a :class:`scenarios.scenes.scene.Scene` or a System).

    The components are the master's in-process instances, initialised and stepped by the
    master's own loop (:class:`fmus.cosim.stepper.Stepper`, Gauss-Seidel order); only the plant's
    step (the continuous block) and, coupled monolithically, the drives' (their voltage
    sample) are the reference's.

    Parameters
    ----------
    rtol, atol : float
        Tolerances of solve_ivp over each sample interval (atol on every state: m, rad,
        m/s, rad/s, A).
    stop_time : float, optional
        Default: the system's.
    method : str
        solve_ivp method (DOP853 by default; see docs/reference.md for why not Radau).
    coupling : {"monolithic", "held_speed", "cosim", "mean"}
        ``"monolithic"`` is the reference; the others are diagnostics (module docstring).
    system_changes : callable, optional
        ``System -> System`` applied before running (e.g. to change a parameter).

    Returns
    -------
    ReferenceResult
        Keeps the rows so far and sets ``error`` when a component refused a step.
    """
    from scenarios.scenes.scene import Scene

    if coupling not in COUPLINGS:
        raise ValueError(f"coupling = {coupling!r}; valid: {', '.join(COUPLINGS)}")
    scene, system = _system_of(scene_or_name, stop_time, system_changes)
    h, steps = system.step, system.steps
    plant_name = _the_plant(system)
    instances = _instances(system)
    order = stepping_order(system, {n: inst.variables for n, inst in instances.items()})
    # Every output recorded; the plant and the drives step once per interval (no sub-steps).
    names = [f"{n}.{v}" for n in order for v in _real_outputs(instances[n])]
    replaced = {plant_name, *_driving(system, plant_name)}
    system = replace(system, record=tuple(names), components=tuple(
        replace(c, substeps=1) if c.name in replaced else c for c in system.components))
    plant = _IntegratedPlant(instances[plant_name], coupling, (method, rtol, atol))
    wrap = {"monolithic": _SampledDrive, "held_speed": _SampledDrive, "mean": _MeanTorqueDrive}.get(coupling)
    drives = {name: wrap(instances[name]) for name in _driving(system, plant_name)} if wrap else {}
    stepper = Stepper(system, {**instances, plant_name: plant, **drives}, order)
    try:
        stepper.initialize(0.0)
    except CoSimulationError as exc:
        raise ReferenceError(str(exc)) from None
    for name, inst in instances.items():
        if inst.slave.error:
            raise ReferenceError(f"{name}: {inst.slave.error}")
    links = _links(system, instances, order, plant_name, coupling)
    for name, drive in drives.items():
        drive.link = links[name]
    monolithic = coupling in ("monolithic", "held_speed")
    plant.couple(_Continuous(plant.slave.sim, list(links.values()) if monolithic else [], coupling == "held_speed"),
                 list(links.values()), stepper)

    rows, error = [stepper.row()], None
    start = _time.perf_counter()
    report_every = max(1, steps // 100)
    for k in range(steps):
        try:
            stepper.step()
        except (CoSimulationError, ReferenceError) as exc:
            error = str(exc)
            break
        rows.append(stepper.row())
        if progress is not None and (k + 1) % report_every == 0:
            progress((k + 1) / steps)
    wall = _time.perf_counter() - start
    data = np.array(rows)
    signals = {s: data[:, j] for j, s in enumerate(names)}
    time = np.arange(len(rows)) * h
    columns = {"t": time}
    if isinstance(scene, Scene):
        columns.update({name: signals[signal] for name, signal in scene.columns.items() if signal in signals})
    return ReferenceResult(time, signals, columns, tuple(order), coupling, method, rtol, atol, wall,
                           plant.nfev, plant.steps, error,
                           extra={"stop_time": system.stop_time, "plant": plant_name,
                                  "mean_steps_per_interval": plant.steps / max(1, len(rows) - 1)})


def common_rows(time_a, time_b) -> tuple[np.ndarray, np.ndarray]:
    """Row indices (ia, ib) at which the two time grids meet (to 1 ns), in time order: all rows
    for equal steps, every second reference row for a run at twice the step."""
    ka = np.round(np.asarray(time_a) * 1e9).astype(np.int64)
    kb = np.round(np.asarray(time_b) * 1e9).astype(np.int64)
    _, ia, ib = np.intersect1d(ka, kb, assume_unique=True, return_indices=True)
    return ia, ib


def deviation(result, reference, start: float = 0.0, end: float | None = None) -> dict:
    """End-effector deviation of ``result`` (a master Result or a ReferenceResult) from ``reference``.

    Over the rows at common times (:func:`common_rows`) with start <= t <= end: ``rms`` =
    sqrt(mean(dx² + dy²)) and ``max`` of the distance [m], ``t_max`` where it is largest;
    signals ``<plant>.x``, ``.y``.
    """
    ia, ib = common_rows(result.time, reference.time)
    t = reference.time[ib]
    keep = (t >= start - 1e-12) & (t <= (math.inf if end is None else end) + 1e-12)
    plant = _plant_prefix(reference)
    dx = (result[f"{plant}.x"][ia] - reference[f"{plant}.x"][ib])[keep]
    dy = (result[f"{plant}.y"][ia] - reference[f"{plant}.y"][ib])[keep]
    d = np.hypot(dx, dy)
    if not d.size:
        return {"rms": float("nan"), "max": float("nan"), "t_max": float("nan"), "rows": 0}
    return {"rms": float(np.sqrt(np.mean(d * d))), "max": float(np.max(d)),
            "t_max": float(t[keep][np.argmax(d)]), "rows": int(d.size)}


def encoder_differences(result, reference) -> tuple[int, float]:
    """(samples at which an encoder reading of ``result`` differs from the reference's, the
    first one's time [s] or nan) over the rows at common times; signals ``<plant>.q1_enc``,
    ``.q2_enc``."""
    ia, ib = common_rows(result.time, reference.time)
    plant = _plant_prefix(reference)
    differs = np.zeros(len(ia), dtype=bool)
    for signal in (f"{plant}.q1_enc", f"{plant}.q2_enc"):
        differs |= np.asarray(result[signal])[ia] != np.asarray(reference[signal])[ib]
    first = float(reference.time[ib][int(np.argmax(differs))]) if differs.any() else float("nan")
    return int(differs.sum()), first


def _plant_prefix(reference) -> str:
    return reference.extra.get("plant", "plant") if isinstance(reference, ReferenceResult) else "plant"


def with_parameters(system: System, instance: str, component_substeps: int | None = None,
                    **parameters) -> System:
    """``system`` with component ``instance``'s parameters updated (and the master's
    multi-rate ``Component.substeps``, if given)."""
    components = []
    for c in system.components:
        if c.name == instance:
            c = replace(c, parameters={**c.parameters, **parameters},
                        substeps=c.substeps if component_substeps is None else component_substeps)
        components.append(c)
    if not any(c.name == instance for c in system.components):
        raise KeyError(instance)
    return replace(system, components=tuple(components))


# --- measurements (docs/reference.md) -----------------------------------------------------

def _windows(stop: float, scene) -> list:
    from scenarios.scenes.scene import Scene

    edges = [0.0, min(0.1, stop)]
    if isinstance(scene, Scene) and scene.reference_end < stop:
        edges += [scene.reference_end]
    edges += [stop]
    return [(a, b) for a, b in zip(edges, edges[1:]) if b > a]


def main(argv=None) -> int:
    """``python -m scenarios.reference [SCENE] [--stop-time S] [--convergence] [--variants]``:
    the reference, the master's deviation from it, and where it comes from."""
    import argparse

    from fmus.cosim.master import simulate

    from scenarios.scenes.catalogue import get_scene

    parser = argparse.ArgumentParser(prog="python -m scenarios.reference", description=main.__doc__)
    parser.add_argument("scene", nargs="?", default="bench_circle_TCMDx")
    parser.add_argument("--stop-time", type=float, default=None)
    parser.add_argument("--rtol", type=float, default=RTOL)
    parser.add_argument("--atol", type=float, default=ATOL)
    parser.add_argument("--convergence", action="store_true", help="rerun with rtol/2 and rtol/10")
    parser.add_argument("--variants", action="store_true",
                        help="decompose the deviation (coupling, plant substeps, encoder, friction)")
    args = parser.parse_args(argv)
    scene = get_scene(args.scene)
    system = scene.system if args.stop_time is None else replace(scene.system, stop_time=args.stop_time)
    stop = system.stop_time
    windows = _windows(stop, scene)

    def line(label, result, reference):
        parts = [f"{label:<44s}"]
        whole = deviation(result, reference)
        parts.append(f"all: rms {whole['rms']:.2e} max {whole['max']:.2e} (t {whole['t_max']:.3f})")
        for a, b in windows:
            d = deviation(result, reference, a, b)
            parts.append(f"[{a:g},{b:g}]: rms {d['rms']:.2e} max {d['max']:.2e}")
        print(" | ".join(parts), flush=True)

    def run(changes=lambda s: s, **kwargs):
        return reference_run(changes(system), rtol=kwargs.pop("rtol", args.rtol),
                             atol=kwargs.pop("atol", args.atol), **kwargs)

    ref = run()
    print(f"{scene.name}, 0-{stop:g} s: reference {ref.method} rtol {ref.rtol:g} atol {ref.atol:g}, "
          f"{ref.wall_s:.1f} s wall, {ref.nfev} evaluations, {ref.extra['mean_steps_per_interval']:.2f} "
          f"steps per interval{'' if ref.completed else ', STOPPED: ' + ref.error}", flush=True)
    if args.convergence:
        for factor in (2, 10):
            line(f"reference at rtol, atol / {factor}", run(rtol=args.rtol / factor, atol=args.atol / factor), ref)
    master = simulate(system)
    print(f"master (in-process, defaults): {master.wall_s:.1f} s wall"
          f"{'' if master.completed else ', STOPPED: ' + str(master.error)}", flush=True)
    line("master - reference", master, ref)
    if not args.variants:
        return 0
    plant = ref.extra["plant"]
    drives = [c.name for c in system.components if c.model == "DCMotorDrive"]
    if drives:
        cosim = run(coupling="cosim")
        held = run(coupling="held_speed")
        line("reference(cosim coupling) - reference", cosim, ref)
        line("  master - reference(cosim): plant RK4", master, cosim)
        line("  ref(cosim) - ref(held_speed): torque held", cosim, held)
        line("  ref(held_speed) - reference: speed held", held, ref)
        line("reference(mean torque) - reference", run(coupling="mean"), ref)
    line("master, plant RK4 substeps=4 - reference", simulate(with_parameters(system, plant, substeps=4)), ref)
    line("master, plant Component substeps=4 - ref.",
         simulate(with_parameters(system, plant, component_substeps=4)), ref)
    variants = []
    if any(c.source.startswith(f"{plant}.q1_enc") or c.source.startswith(f"{plant}.q2_enc")
           for c in system.connections):
        variants.append(("encoder 2^30 counts", lambda s: with_parameters(s, plant, encoder_counts=2 ** 30)))
    if drives:
        def no_friction(s):
            for d in drives:   # LuGre needs mu > 0: its drives lose the LuGre model too
                lugre = s.component(d).parameters.get("friction") == "lugre"
                s = with_parameters(s, d, mu=0.0, **({"friction": "tanh"} if lugre else {}))
            return s
        variants.append(("mu = 0", no_friction))
        if variants[0][0].startswith("encoder"):
            variants.append(("mu = 0 and encoder 2^30", lambda s: variants[0][1](no_friction(s))))
    for label, changes in variants:
        line(f"{label}: master - reference", simulate(changes(system)), run(changes))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
