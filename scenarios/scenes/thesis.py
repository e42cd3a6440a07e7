"""The thesis' scenes as data: which components, their parameters, the wiring, what to record.

Each scene is a :class:`scenarios.scenes.scene.Scene`: a :class:`fmus.cosim.system.System` plus
what the metrics need (the trajectory's end and the metric windows, thesis 7.31-7.32).  A scene models only what
it needs: ``thesis_sim_circle`` has no motors, observers or derivator (ideal torque
actuators, exact measurements); the bench scenes have the whole chain.

Names (:func:`scenarios.scenes.catalogue.scene_names`): ``thesis_sim_circle`` (model error 0 %) and
``thesis_sim_circle_me20`` / ``_me40`` (20 %, 40 %, thesis figures 12-23);
``bench_circle_<S>`` and ``bench_triangle_<S>`` for the eight strategies S of 7.2.6 and seed
001's two (SMCq, SMCx); ``bench_real_circle_<S>``, ``bench_real_triangle_<S>``: the bench twin
(:mod:`scenarios.scenes.twin`, the eight strategies); ``vertical_circle_<S>`` and ``vertical_circle_balanced_<S>``: the bench
in a vertical plane, without and with counter-masses (:func:`vertical_circle`, docs/balanced.md).

Copy a builder (:func:`thesis_sim_circle`, :func:`bench`) to make your own scene; every
parameter not given keeps the FMU's default (the presets of Tables 3-8, 16, 18).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from controller.strategies import ALL_STRATEGY_NAMES
from controller.trajectories import from_parameters
from fmus.cosim.system import Component, Connection, System
from motor import get_motor_preset
from motor.drive import FRICTION_MODELS
from scenarios.scenes.scene import SETTLE_TIME, Scene

REFERENCE_SIGNALS = ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")


ELECTRICS = ("full", "euler", "quasi_static", "ideal")
#: The drives hand the plant their torque averaged over the step: chosen from the
#: speed/accuracy front (docs/trade.md: same cost, peak deviation from the monolithic
#: reference 9.3e-5 -> 3.5e-5 m on bench_circle_TCMDx).
DRIVE_TORQUE_OUTPUT = "mean"


@dataclass(frozen=True)
class Fidelity:
    """Which effects a bench scene models; an effect switched off costs nothing.

    Parameters
    ----------
    electrics : {"full", "euler", "quasi_static", "ideal"}
        Motor electrics: exact zero-order-hold solution of L di/dt + R i + ke ω = v
        ("full"), explicit Euler, quasi-static (the drive's method "quasi_static": the
        current follows the voltage at once, i = (v - ke ω)/R), or "ideal": torque sources —
        no drive or observer components at all, the controller's torques go to the plant
        (and there is no motor friction).  Euler and quasi-static simplify the motor model
        only: the current controller stays the one designed for the real motor (with its L),
        as the bench's drive would run it.
    coulomb, viscous : bool
        The drives' Coulomb (μ) and viscous (b) friction.
    encoder : bool
        The derivator and the controller read the 20000-count encoder angles (else the
        exact angles).
    observer : bool
        The current loops read the observed current (7.20; else the drive's own current,
        and there are no observer components).
    derivator : bool
        The controller reads the derivator's estimates (else the plant's exact speeds and
        zero accelerations: no derivator component).
    link_inertias : bool
        The links' Jz (else point masses).
    m0 : float
        End-effector mass [kg].
    gravity : (float, float, float)
        World gravity [m/s²]; the thesis' plane is horizontal (0, 0, g) has no effect.
    model_error : float
        The controller model's inertial parameters are (1 + model_error) times the plant's.
    counter_masses : (float, float)
        ``counter_mass1``, ``counter_mass2`` of the plant [kg] (seed 001's balanced 5R); the
        controller's model has them too.
    model_gravity : bool
        The controller's model has the plant's in-plane gravity (else it assumes none).
    delay_steps : int
        Computation delay: the controller's commands (torques, current references) are
        applied this many 1 ms samples after they were computed (the bench twin: 1).
    friction : {"tanh", "lugre"}
        The drives' dry friction: the regularised Coulomb mu tanh(ω/omega_eps) of B.2, or the
        LuGre model with stiction (motor/friction.py, the motor presets' mu_s, omega_s,
        sigma0, sigma1; docs/friction.md).  "lugre" needs ``coulomb``.
    pwm_counts : int
        The drives' PWM resolution: applied voltages are multiples of v_max / pwm_counts
        (0: ideal).
    current_offset, current_noise : float
        Offset [A] and standard deviation [A] of a Gaussian noise on the current each drive's
        current loop reads (the observed i_hat on the bench; docs/friction.md).
    noise_seed : int
        The noise's seed; drive j draws instance j: sample k's noise is a function of
        (noise_seed, j, k) only.
    drive_parameters : tuple of (str, value) pairs
        More DCMotorDrive parameters set on both drives (e.g. (("mu_s", 0.06),)).
    """

    electrics: str = "full"
    coulomb: bool = True
    viscous: bool = True
    encoder: bool = True
    observer: bool = True
    derivator: bool = True
    link_inertias: bool = True
    m0: float = 0.0
    gravity: tuple = (0.0, 0.0, 0.0)
    model_error: float = 0.0
    counter_masses: tuple = (0.0, 0.0)
    model_gravity: bool = False
    delay_steps: int = 0
    friction: str = "tanh"
    pwm_counts: int = 0
    current_offset: float = 0.0
    current_noise: float = 0.0
    noise_seed: int = 0
    drive_parameters: tuple = ()

    def __post_init__(self):
        if self.electrics not in ELECTRICS:
            raise ValueError(f"electrics = {self.electrics!r}; valid: {', '.join(ELECTRICS)}")
        if self.friction not in FRICTION_MODELS:
            raise ValueError(f"friction = {self.friction!r}; valid: {', '.join(FRICTION_MODELS)}")
        if self.friction == "lugre" and not self.coulomb:
            raise ValueError("friction = 'lugre' models the dry friction that coulomb = False removes")
        if self.electrics == "ideal" and self.drive_options():
            raise ValueError("electrics = 'ideal' has no drives for friction, pwm_counts, current_offset, "
                             "current_noise, noise_seed or drive_parameters")

    def drive_options(self) -> dict:
        """The DCMotorDrive parameters these effects set (the same for both drives, but
        ``noise_instance``, which :func:`bench` sets to the drive's number)."""
        options = {} if self.friction == "tanh" else {"friction": self.friction}
        for name, off in (("pwm_counts", 0), ("current_offset", 0.0), ("current_noise", 0.0), ("noise_seed", 0)):
            if getattr(self, name) != off:
                options[name] = getattr(self, name)
        options.update(dict(self.drive_parameters))
        return options


def _connect(pairs):
    return tuple(Connection(s, t) for s, t in pairs)


def _reference_wiring(trajectory="traj", controller="ctrl"):
    return [(f"{trajectory}.{s}", f"{controller}.{s}") for s in REFERENCE_SIGNALS]


_COLUMNS = {"x": "plant.x", "y": "plant.y", "x_d": "traj.x_d", "y_d": "traj.y_d",
            "tau1": "ctrl.tau1", "tau2": "ctrl.tau2", "q1": "plant.q1", "q2": "plant.q2",
            "e1": "ctrl.e1", "e2": "ctrl.e2", "residual": "plant.residual"}


def thesis_sim_circle(model_error: float = 0.0, lam: float = 40.0, model: str = "exact",
                      cycles: int = 2) -> Scene:
    """Section 7.1.5: Table 3 mechanism, ideal torque actuators, TCx with lambda = 40, circle 7.18.

    The controller reads the plant's exact angles and velocities (no derivator, no motors);
    its model's inertial parameters are ``1 + model_error`` times the plant's.
    """
    reference = {"kind": "thesis_circle", "cycles": cycles}
    trajectory = from_parameters(**reference)
    x0, y0 = trajectory.start_point
    components = (
        Component("traj", "Trajectory", reference),
        Component("ctrl", "PositionController", {
            "strategy": "TCx", "lam": lam, "model": model, "model_error": model_error,
            "preset": "thesis_sim"}),
        Component("plant", "FiveBarPlant", {"preset": "thesis_sim", "x0": x0, "y0": y0}),
    )
    wiring = _reference_wiring() + [(f"plant.{s}", f"ctrl.{s}") for s in ("q1", "q2", "dq1", "dq2")]
    wiring += [("ctrl.tau1", "plant.tau1"), ("ctrl.tau2", "plant.tau2")]
    columns = dict(_COLUMNS)
    system = System(components, _connect(wiring), tuple(dict.fromkeys(columns.values())),
                    stop_time=trajectory.duration)
    suffix = "" if model_error == 0.0 else f"_me{round(100 * model_error)}"
    return Scene(f"thesis_sim_circle{suffix}",
                 f"Simulation of 7.1.5: ideal actuators, TCx lambda={lam:g}, model error {100 * model_error:g} %",
                 system, columns, (1.0, trajectory.duration), trajectory.duration, "TCx")


def bench(strategy: str, kind: str = "circle", model: str = "tabulated",
          fidelity: Fidelity = Fidelity()) -> Scene:
    """The bench of 7.2: plant with rotors and encoders, two drives with their current loops
    and observers, the derivator, the controller with ``strategy`` (Tables 6-8), the trajectory.

    Wiring (the real bench): the derivator and the controller read the encoder angles; the
    observers read the drives' voltages and the derivator's velocities; the drives read the
    current references, the observed currents and the true shaft speeds.  ``fidelity``
    switches effects off (:class:`Fidelity`); the components they need go with them.
    """
    if strategy not in ALL_STRATEGY_NAMES:
        raise ValueError(f"strategy = {strategy!r}; valid: {', '.join(ALL_STRATEGY_NAMES)}")
    f = fidelity
    trajectory = from_parameters(kind)
    x0, y0 = trajectory.start_point
    drives = f.electrics != "ideal"
    observers = drives and f.observer
    plant = {"preset": "bench", "x0": x0, "y0": y0, "m0": f.m0, "link_inertias": f.link_inertias,
             "gravity_x": f.gravity[0], "gravity_y": f.gravity[1], "gravity_z": f.gravity[2]}
    components = [Component("traj", "Trajectory", {"kind": kind})]
    if f.derivator:
        components.append(Component("deriv", "Derivator", {}))
    controller = {"strategy": strategy, "trajectory": kind, "model": model, "preset": "bench",
                  "model_error": f.model_error}
    if f.counter_masses != (0.0, 0.0):
        loads = {"counter_mass1": f.counter_masses[0], "counter_mass2": f.counter_masses[1]}
        plant.update(loads)
        controller.update(loads)
    if f.model_gravity:
        controller.update(gravity_x=f.gravity[0], gravity_y=f.gravity[1])
    if f.delay_steps:
        controller["delay_steps"] = f.delay_steps
    components.append(Component("ctrl", "PositionController", controller))
    for j in ("1", "2"):
        if observers:
            components.append(Component(f"obs{j}", "CurrentObserver", {"preset": f"motor{j}"}))
    for j in ("1", "2"):
        if drives:
            drive = {"preset": f"motor{j}", "mode": "current", "torque_output": DRIVE_TORQUE_OUTPUT,
                     "method": "exact" if f.electrics == "full" else f.electrics}
            if not f.coulomb:
                drive["mu"] = 0.0
            if not f.viscous:   # the current loop stays designed for the real motor's b
                drive["b"] = 0.0
                drive["b_design"] = get_motor_preset(f"motor{j}").b
            drive.update(f.drive_options())
            if f.current_noise:
                drive["noise_instance"] = int(j)
            components.append(Component(f"drive{j}", "DCMotorDrive", drive))
    components.append(Component("plant", "FiveBarPlant", plant))
    angle = "_enc" if f.encoder else ""
    wiring = _reference_wiring()
    for j in ("1", "2"):
        wiring.append((f"plant.q{j}{angle}", f"ctrl.q{j}"))
        if f.derivator:
            wiring += [(f"plant.q{j}{angle}", f"deriv.q{j}"),
                       (f"deriv.dq{j}", f"ctrl.dq{j}"), (f"deriv.ddq{j}", f"ctrl.ddq{j}")]
        else:
            wiring.append((f"plant.dq{j}", f"ctrl.dq{j}"))
        if drives:
            wiring += [(f"ctrl.i_ref{j}", f"drive{j}.i_ref"), (f"plant.dq{j}", f"drive{j}.omega"),
                       (f"drive{j}.tau", f"plant.tau{j}")]
            if observers:
                speed = f"deriv.dq{j}" if f.derivator else f"plant.dq{j}"
                wiring += [(f"obs{j}.i_hat", f"drive{j}.i_hat"), (f"drive{j}.v", f"obs{j}.v"),
                           (speed, f"obs{j}.omega")]
            else:
                wiring.append((f"drive{j}.i", f"drive{j}.i_hat"))
        else:
            wiring.append((f"ctrl.tau{j}", f"plant.tau{j}"))
    columns = dict(_COLUMNS)
    if drives:
        columns.update({"i1": "drive1.i", "i2": "drive2.i", "v1": "drive1.v", "v2": "drive2.v",
                        "tau1_shaft": "drive1.tau", "tau2_shaft": "drive2.tau"})
    if observers:
        columns.update({"i_hat1": "obs1.i_hat", "i_hat2": "obs2.i_hat"})
    system = System(tuple(components), _connect(wiring), tuple(dict.fromkeys(columns.values())),
                    stop_time=trajectory.duration + SETTLE_TIME)
    window = (1.0, 8.0) if kind == "circle" else (0.0, trajectory.duration)
    name = f"bench_{kind}_{strategy}"
    description = f"Bench of 7.2, {kind} trajectory, strategy {strategy} (Tables 6-8), {model} model"
    if f != Fidelity():
        changed = {k: getattr(f, k) for k in f.__dataclass_fields__ if getattr(f, k) != getattr(Fidelity(), k)}
        description += "; fidelity " + ", ".join(f"{k}={v}" for k, v in changed.items())
    return Scene(name, description, system, columns, window, trajectory.duration, strategy)


#: Gravity of the vertical scenes: the mechanism's plane vertical, world y up (the brief ../shared/spec/SYSTEM.md §2).
VERTICAL_GRAVITY = (0.0, -9.81, 0.0)
#: Counter-masses of the balanced vertical scenes [kg] on each chain's proximal and distal
#: link, placed by seed 001 (64): 0.4 kg 0.107 m (chain 1) / 0.098 m (chain 2) behind the
#: base joints, 0.2 kg 0.048 m / 0.028 m behind the elbows (docs/balanced.md).
VERTICAL_COUNTER_MASSES = (0.4, 0.2)


def vertical_circle(strategy: str, balanced: bool = False, model: str = "tabulated",
                    fidelity: Fidelity = Fidelity(), frequency: float = 1.0) -> Scene:
    """The bench (:func:`bench`) standing in a vertical plane, tracking the circle (7.23).

    Gravity :data:`VERTICAL_GRAVITY` acts in the mechanism's plane; ``balanced`` adds the
    counter-masses :data:`VERTICAL_COUNTER_MASSES` (seed 001's balanced 5R).  The controller's
    model (Ĥ, ĥ of 5.74-5.77) has the same gravity and counter-masses as the plant.
    ``frequency`` [Hz] runs the circle's 8 turns faster or slower (the scenes: 1 Hz, as 7.23);
    the metric window is then turns 2 to 8.
    """
    counter = VERTICAL_COUNTER_MASSES if balanced else (0.0, 0.0)
    f = replace(fidelity, gravity=VERTICAL_GRAVITY, model_gravity=True, counter_masses=counter)
    scene = bench(strategy, "circle", model, f)
    if frequency != 1.0:
        reference = {**scene.system.component("traj").parameters, "frequency": frequency}
        trajectory = from_parameters(**reference)
        components = tuple(replace(c, parameters=reference) if c.name == "traj" else c
                           for c in scene.system.components)
        system = replace(scene.system, components=components, stop_time=trajectory.duration + SETTLE_TIME)
        scene = replace(scene, system=system, window=(1.0 / frequency, trajectory.duration),
                        reference_end=trajectory.duration)
    name = f"vertical_circle_{'balanced_' if balanced else ''}{strategy}"
    what = (f"counter-masses {counter[0]:g} kg (proximal) and {counter[1]:g} kg (distal) on each chain"
            if balanced else "no counter-masses")
    return replace(scene, name=name,
                   description=f"Bench of 7.2 in a vertical plane (gravity -9.81 m/s² along -y), {what}, "
                               f"circle (7.23) at {frequency:g} Hz, strategy {strategy}, {model} model with the same gravity "
                               f"and masses")
