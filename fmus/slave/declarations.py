"""Variable declarations and model construction that several slaves share.

``FiveBarPlant`` and ``ActuatedFiveBarPlant`` declare the same mechanism parameters and
outputs; ``DCMotorDrive`` and ``ActuatedFiveBarPlant`` the same motor parameters (the
latter once per drive, with a suffix 1 or 2).  Declared once here, so an FMU variable
means the same thing in every FMU that has it.  Bundled into every FMU with
:mod:`fmus.slave.base`.
"""
from __future__ import annotations

import math
from dataclasses import replace

from fmus.slave import budget
from fmus.slave import sampling
from fmus.slave.refusals import (PRESET_VALUE, TINY, motor_preset, refuse_absurd, refuse_tiny, require_finite,
                           with_overrides)

#: The plant's outputs (name, description).
PLANT_OUTPUTS = (
    ("q1", "Chain 1 actuated angle, CCW from +x [rad]"),
    ("q2", "Chain 2 actuated angle, CCW from +x [rad]"),
    ("dq1", "d q1/dt [rad/s]"), ("dq2", "d q2/dt [rad/s]"),
    ("x", "End effector x [m]"), ("y", "End effector y [m]"),
    ("dx", "d x/dt [m/s]"), ("dy", "d y/dt [m/s]"),
    ("q1_enc", "q1 quantised to encoder counts [rad]"),
    ("q2_enc", "q2 quantised to encoder counts [rad]"),
    ("residual", "Norm of the loop-closure residual (5.18) [m]"),
)

#: Motor parameters settable one by one (MotorParams field, FMU variable, description).
MOTOR_PARAMETERS = (
    ("R", "R", "Armature resistance [ohm], > 0"),
    ("L", "L", "Armature inductance [H], >= 0 (0: quasi-static, voltage mode only)"),
    ("kt", "kt", "Torque constant [N m/A], > 0"),
    ("ke", "ke", "Back-emf constant [V s/rad], > 0"),
    ("b", "b", "Viscous friction [N m s/rad], >= 0"),
    ("mu", "mu", "Coulomb friction torque [N m], >= 0"),
    ("v_max", "v_max", "Supply voltage: the driver saturates at +-v_max [V], > 0"),
    ("omega_eps", "omega_eps", "Width of the regularised sign mu*tanh(omega/omega_eps) [rad/s], > 0"),
    ("mu_s", "mu_s", "LuGre break-away torque Fs (friction 'lugre') [N m], >= mu"),
    ("omega_s", "omega_s", "LuGre Stribeck speed (friction 'lugre') [rad/s], > 0"),
    ("sigma0", "sigma0", "LuGre bristle stiffness (friction 'lugre') [N m/rad], > 0"),
    ("sigma1", "sigma1", "LuGre bristle damping (friction 'lugre') [N m s/rad], >= 0"),
    ("J_rotor", "J_design", "Rotor inertia assumed by the current-controller design G_I(s) (B.10) only "
                            "[kg m2], > 0; the plant integrates the real rotor inertia"),
)

#: A drive's options beyond its motor (FMU variable, start value, description): its friction
#: model and the bench's imperfections (:class:`motor.Drive`; all off by default).
DRIVE_OPTIONS = (
    ("friction", "tanh", "Shaft friction: 'tanh' (mu tanh(omega/omega_eps) + b omega, B.2) or 'lugre' "
                         "(LuGre with stiction: mu, mu_s, omega_s, sigma0, sigma1, b; motor/friction.py)"),
    ("pwm_counts", 0, "PWM resolution: the applied voltage is a multiple of v_max/pwm_counts (0: ideal)"),
    ("current_offset", 0.0, "Offset of the current the current loop reads (current mode) [A]"),
    ("current_noise", 0.0, "Standard deviation of a Gaussian noise on the current the current loop reads [A]"),
    ("noise_seed", 0, "Seed of that noise: sample k's noise is a function of (noise_seed, noise_instance, k)"),
    ("noise_instance", 0, "Instance of that noise (give each drive its own)"),
)

#: The current-controller design's own motor parameters (MotorParams field, FMU variable): a
#: drive whose motor differs from the one its controller was designed for (a model error,
#: ``parcosim sweep``) keeps its design.  ``J_design`` is the design's only rotor inertia
#: (:data:`MOTOR_PARAMETERS`); these default to the drive's own value.
DESIGN_PARAMETERS = (("R", "R_design"), ("L", "L_design"), ("kt", "kt_design"), ("ke", "ke_design"),
                     ("b", "b_design"))

#: Per-chain mechanism parameters settable one by one (ChainParams field, description):
#: FMU variables ``chain<k>_<field>`` for chain k = 1, 2 (Tables 3-5).
CHAIN_PARAMETERS = (
    ("l1", "Proximal link length [m], > 0"),
    ("l2", "Distal link length [m], > 0"),
    ("lg1", "Proximal link: centre of mass from its base joint [m]"),
    ("lg2", "Distal link: centre of mass from its elbow joint [m]"),
    ("m1", "Proximal link mass [kg]"),
    ("m2", "Distal link mass [kg]"),
    ("Jz1", "Proximal link inertia about its centre of mass [kg m2]"),
    ("Jz2", "Distal link inertia about its centre of mass [kg m2]"),
)


# --- the plant -------------------------------------------------------------------------------

def declare_plant(slave) -> None:
    """The mechanism's outputs and parameters (thesis ch. 7.1, Tables 3-5)."""
    from plant import ENCODER_COUNTS, IntegratorSettings

    defaults = IntegratorSettings()
    d = slave.declare
    for name, text in PLANT_OUTPUTS:
        d(name, "output", 0.0, text)
    d("preset", "parameter", "thesis_sim", "Mechanism parameters: 'thesis_sim' (Table 3) or 'bench' (Tables 4-5)")
    d("x0", "parameter", 0.07, "Start at rest with the end effector at (x0, y0) [m]")
    d("y0", "parameter", 0.17, "Start at rest with the end effector at (x0, y0) [m]")
    d("J_rotor1", "parameter", PRESET_VALUE, "Rotor inertia on q1 [kg m2]; -1: the preset's (bench: Table 16)")
    d("J_rotor2", "parameter", PRESET_VALUE, "Rotor inertia on q2 [kg m2]; -1: the preset's (bench: Table 18)")
    d("m0", "parameter", 0.0, "End-effector point mass [kg]")
    d("l0", "parameter", 0.05, "Half the distance between the base joints [m]")
    d("gravity_x", "parameter", 0.0, "Gravity, world x [m/s2]")
    d("gravity_y", "parameter", 0.0, "Gravity, world y [m/s2]")
    d("gravity_z", "parameter", 0.0, "Gravity, world z [m/s2] (no effect on the planar motion)")
    d("link_inertias", "parameter", True, "Links have their inertias Jz (false: point masses at the centres of mass)")
    d("encoder_counts", "parameter", ENCODER_COUNTS, "Encoder counts per revolution (quadrature)")
    for k in (1, 2):
        for field, text in CHAIN_PARAMETERS:
            d(f"chain{k}_{field}", "parameter", PRESET_VALUE, f"Chain {k}: {text}; -1: the preset's value")
        d(f"encoder_offset{k}", "parameter", 0.0,
          f"Encoder {k} zero error: q{k}_enc reads q{k} + encoder_offset{k}, quantised [rad]")
    d("method", "parameter", defaults.method, "Integrator: 'rk4' (fixed step) or 'dopri5' (adaptive)")
    d("substeps", "parameter", defaults.substeps, "RK4 steps per communication step")
    d("rtol", "parameter", defaults.rtol, "Relative tolerance of dopri5")
    d("atol", "parameter", defaults.atol, "Absolute tolerance of dopri5")
    d("baumgarte", "parameter", defaults.baumgarte, "Baumgarte lambda of (5.66) [1/s]")
    d("project", "parameter", defaults.project, "Project q, dq on the constraints after each step")
    d("kernel", "parameter", defaults.kernel, "'fast' (compiled 5R) or 'general' (thesis algorithm in numpy)")
    declare_counter_masses(slave)


def declare_counter_masses(slave) -> None:
    """``counter_mass1``, ``counter_mass2``: the balanced 5R of seed 001 (the brief ../shared/spec/SYSTEM.md §7)."""
    for j, link in (("1", "proximal"), ("2", "distal")):
        slave.declare(f"counter_mass{j}", "parameter", 0.0,
                      f"Counter-mass on each chain's {link} link, behind its joint where seed 001 (64) puts it "
                      f"(each chain's gravity terms vanish) [kg]; 0: none; needs m0 = 0")


def with_counter_masses(slave, params):
    """``params`` with the slave's ``counter_mass1``/``counter_mass2`` (checked, named)."""
    values = {name: getattr(slave, name) for name in ("counter_mass1", "counter_mass2")}
    require_finite(**values)
    refuse_absurd(**values)
    for name, value in values.items():
        if value < 0.0:
            raise ValueError(f"parameter {name} = {value!r} kg must be >= 0")
    params = params.with_counter_masses(values["counter_mass1"], values["counter_mass2"])
    # counter_mass<j> is link j's mass on both chains: a mass too light is named so
    params.check_counter_masses(name=lambda k, j: f"parameter counter_mass{j}")
    return params


def build_plant(slave):
    """The :class:`plant.PlantSimulator` the slave's plant parameters describe."""
    from plant import IntegratorSettings, PlantSimulator, get_preset

    params = get_preset(slave.preset)
    numeric = {name: getattr(slave, name) for name in (
        "J_rotor1", "J_rotor2", "m0", "l0", "gravity_x", "gravity_y", "gravity_z", "baumgarte", "rtol", "atol")}
    require_finite(**numeric)
    refuse_absurd(**numeric)
    refuse_tiny(l0=slave.l0)     # base joints 1e-300 m apart: no mechanism (the models' own check wants > 0)
    for name in ("J_rotor1", "J_rotor2"):
        value = getattr(slave, name)
        if value < 0.0 and value != PRESET_VALUE:
            raise ValueError(f"{name} = {value!r} must be >= 0 (or -1 for the preset's value)")
    params = params.with_rotors(
        params.chain1.J_rotor if slave.J_rotor1 == PRESET_VALUE else slave.J_rotor1,
        params.chain2.J_rotor if slave.J_rotor2 == PRESET_VALUE else slave.J_rotor2,
    )
    params = replace(params, chain1=_chain_overrides(params.chain1, slave, 1),
                     chain2=_chain_overrides(params.chain2, slave, 2))

    params = replace(params, m0=slave.m0, l0=slave.l0,
                     gravity=(slave.gravity_x, slave.gravity_y, slave.gravity_z))
    params = with_counter_masses(slave, params)
    if not slave.link_inertias:
        params = replace(params, chain1=replace(params.chain1, Jz1=0.0, Jz2=0.0),
                         chain2=replace(params.chain2, Jz1=0.0, Jz2=0.0))
    settings = IntegratorSettings(
        method=slave.method, substeps=slave.substeps, rtol=slave.rtol, atol=slave.atol,
        baumgarte=slave.baumgarte, project=bool(slave.project), kernel=slave.kernel,
    )
    offsets = {f"encoder_offset{k}": getattr(slave, f"encoder_offset{k}") for k in (1, 2)}
    require_finite(**offsets)
    refuse_absurd(**offsets)
    sim = PlantSimulator(params, slave.x0, slave.y0, settings, encoder_counts=slave.encoder_counts,
                         encoder_offsets=tuple(offsets.values()))
    budget.check_rk4_substeps(sim, f"parameters kernel = {settings.kernel!r}, substeps = {settings.substeps!r}",
                              "kernel 'fast'")
    return sim


def _chain_overrides(chain, slave, k: int):
    """``chain`` with the slave's ``chain<k>_<field>`` parameters that are not PRESET_VALUE."""
    changes = {}
    for field, _ in CHAIN_PARAMETERS:
        var = f"chain{k}_{field}"
        value = float(getattr(slave, var))
        if value == PRESET_VALUE:
            continue
        require_finite(**{var: value})
        refuse_absurd(**{var: value})
        if value < 0.0 or (field in ("l1", "l2") and value < TINY):
            raise ValueError(f"parameter {var} = {value!r} must be {'> 0' if field in ('l1', 'l2') else '>= 0'} "
                             "(or -1 for the preset's value)")
        changes[field] = value
    return replace(chain, **changes)


def correct_plant(sim, snapshot, measured: dict, redo, step: float) -> bool:
    """Redo the step ``sim`` took from ``snapshot`` = (state, time), from that state made
    consistent with the ``measured`` outputs (:func:`plant.correction.corrected_state`).

    ``redo()`` takes the step again with the inputs held in it.  Returns False, changing
    nothing, when the state agreed with every measurement.
    """
    from plant.correction import corrected_state

    y, time = snapshot
    now = sim.y
    sim.y = y
    z = corrected_state(sim, measured, step)
    if z is None:
        sim.y = now
        return False
    sim.y, sim.time = z, time
    redo()
    return True


def publish_plant(slave, sim) -> None:
    """Copy the plant's outputs to the slave's variables (Python floats already,
    :meth:`plant.simulator.PlantSimulator.output_values`; stored one attribute after another:
    about half the time of a dict built and merged, on every step)."""
    (slave.q1, slave.q2, slave.dq1, slave.dq2, slave.x, slave.y, slave.dx, slave.dy, slave.q1_enc, slave.q2_enc,
     slave.residual) = sim.output_values()


# --- a drive ---------------------------------------------------------------------------------

def declare_motor(slave, suffix: str = "", default_preset: str = "motor1") -> None:
    """A drive's motor parameters (Tables 16, 18): ``preset``, the :data:`MOTOR_PARAMETERS`
    and the :data:`DESIGN_PARAMETERS`, each name followed by ``suffix``."""
    d = slave.declare
    d(f"preset{suffix}", "parameter", default_preset,
      "Motor parameters: 'motor1' (Table 16), 'motor2' (Table 18) or 'seed000' (seed 000's motor)")
    for _, var, text in MOTOR_PARAMETERS:
        d(f"{var}{suffix}", "parameter", PRESET_VALUE, f"{text}; -1: the preset's value")
    for field, var in DESIGN_PARAMETERS:
        d(f"{var}{suffix}", "parameter", PRESET_VALUE,
          f"{field} assumed by the current-controller design only (app. C), > 0; -1: the drive's {field}")


def declare_drive_options(slave, suffix: str = "") -> None:
    """A drive's :data:`DRIVE_OPTIONS`, each name followed by ``suffix``."""
    for name, start, text in DRIVE_OPTIONS:
        slave.declare(f"{name}{suffix}", "parameter", start, text)


def drive_params(slave, suffix: str = ""):
    """The slave's drive's :class:`motor.MotorParams` (the preset with the
    :data:`MOTOR_PARAMETERS` followed by ``suffix`` that are not -1) and those its current
    controller is designed for (:data:`DESIGN_PARAMETERS`; None: the same), checked and named
    as the slave's variables."""
    from motor.presets import POSITIVE_FIELDS

    params = with_overrides(motor_preset(slave, f"preset{suffix}"), slave, motor_variables(suffix),
                            positive=POSITIVE_FIELDS)   # refused below TINY
    changes = {}
    for field, var in DESIGN_PARAMETERS:
        value = getattr(slave, f"{var}{suffix}")
        if value == PRESET_VALUE:
            continue
        refuse_absurd(**{f"{var}{suffix}": value})
        if not (math.isfinite(value) and value >= TINY):
            raise ValueError(f"parameter {var}{suffix} = {value!r} must be > 0 (or -1: the value of {field})")
        changes[field] = value
    return params, (params.with_(**changes) if changes else None)


def build_drive(slave, suffix: str = "", **options):
    """The :class:`motor.Drive` of the slave's motor parameters (:func:`drive_params`) and
    :data:`DRIVE_OPTIONS` with ``suffix``; ``options`` (mode, method, T, torque_output) go
    to the Drive."""
    from motor import Drive
    from motor._checks import BadValue

    params, design = drive_params(slave, suffix)
    values = {name: getattr(slave, f"{name}{suffix}") for name, _, _ in DRIVE_OPTIONS}
    refuse_absurd(**{f"{name}{suffix}": values[name] for name in ("current_offset", "current_noise")})
    try:
        return Drive(params, design_params=design, **options, **values)
    except BadValue as exc:     # named as the slave's variable
        raise exc.renamed(drive_variables(suffix)) from None


def motor_variables(suffix: str = "") -> dict:
    """The FMU variable of each :class:`motor.MotorParams` field settable one by one
    (:data:`MOTOR_PARAMETERS`), followed by ``suffix``."""
    return {field: f"{var}{suffix}" for field, var, _ in MOTOR_PARAMETERS}


def drive_variables(suffix: str = "") -> dict:
    """The FMU variable of each name a :class:`motor.Drive` refuses a value by: its options
    (:data:`DRIVE_OPTIONS`) and the :class:`motor.MotorParams` fields (:func:`motor_variables`),
    followed by ``suffix``."""
    return {**{name: f"{name}{suffix}" for name, _, _ in DRIVE_OPTIONS}, **motor_variables(suffix)}


class CurrentLoopSteps:
    """The step sizes of a slave whose drives' current controllers sample at ``T`` (mixed
    in before :class:`fmus.slave.base.GuardedSlave`: ``DCMotorDrive``, ``ActuatedFiveBarPlant``).

    In current mode a step must divide T (T / h = n a whole number, the same n within a
    period) and ``sample_phase`` be below n: the controllers sample on that sub-step of each
    period (:mod:`fmus.slave.sampling`; the counting is the drive kernel's); in voltage mode any
    step the base accepts.  The subclass lists its drives in :meth:`current_loops`.
    """

    #: Declared with DefaultExperiment stepSize T, not variable steps (:mod:`fmus.slave.sampling`).
    has_sample_period = True

    def to_xml(self, model_options=None):
        return sampling.model_description_with_period(self, super().to_xml, model_options or {})

    def current_loops(self) -> list:
        """The slave's :class:`motor.Drive` objects."""
        raise NotImplementedError

    def accepted_steps(self):
        if self.mode == "current":
            return f"in current mode {sampling.accepted_steps_text()}"
        return super().accepted_steps() + " (voltage mode)"

    def check_step_size(self, current_time, step_size):
        super().check_step_size(current_time, step_size)
        if self.mode != "current":
            return
        n = sampling.checked_substeps(self, current_time, step_size)
        for drive in self.current_loops():
            sampling.check_period_change(self, current_time, step_size, n, drive.substeps, drive.substep)
