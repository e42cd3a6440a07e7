"""The plant with its drives inside (plant/actuated.py, the ActuatedFiveBarPlant FMU, drives_in_plant)."""
from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim.master import simulate
from motor import Drive, friction, get_motor_preset, shaft_torque
from plant import IntegratorSettings, PlantError, PlantSimulator, fast5r, fivebar, get_preset
from plant.actuated import ActuatedPlant
from scenarios.reference import deviation, reference_run
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant

START = (-0.002, 0.108)      # the bench circle's start


def _actuated(kernel="fast", settings=None, **motor_changes):
    settings = settings or IntegratorSettings(kernel=kernel)
    sim = PlantSimulator(get_preset("bench"), *START, settings)
    drives = [(j, Drive(get_motor_preset(f"motor{j}").with_(**motor_changes))) for j in (1, 2)]
    return ActuatedPlant(sim, drives)


def _random_state(a, rng):
    z = a.state()
    z[7:14] += rng.normal(scale=0.3, size=7)
    z[14:] = rng.normal(scale=2.0, size=2)
    return z


def test_c_derivative_equals_the_general_algorithm_with_the_motor_equations():
    """The C kernel's actuated derivative against an independent formulation: the general
    algorithm's forward dynamics (plant.parallel) with motor.shaft_torque and
    motor.armature_current_rate on the world joints (ActuatedPlant.derivative, general kernel)."""
    a = _actuated("general")
    p = fast5r.pack_params(a.plant.params)
    rng = np.random.default_rng(7)
    for _ in range(20):
        z, v = _random_state(a, rng), rng.normal(scale=10.0, size=2)
        external = rng.normal(scale=0.05, size=2)
        expected = a.derivative(z, v, external)
        out = np.empty(16)
        fast5r.actuated_derivative(p, a._motors, z, v, *[float(u) for u in (external[0], -external[1])],
                                   a.plant.settings.baumgarte, out)
        assert np.allclose(out, expected, rtol=1e-12, atol=1e-12 * np.max(np.abs(expected)))


def test_without_drives_it_is_the_plant():
    """Catches an actuated plant that changes the plant's derivative when it holds no drives."""
    a = _actuated()
    bare = ActuatedPlant(a.plant, [])
    z = a.plant.y.copy()
    z[7:] += 0.1
    assert np.array_equal(bare.derivative(z, [], (0.02, -0.03)), a.plant.derivative(z, np.array([0.02, 0.03])))


def test_shaft_torque_and_current_rate_enter_with_the_world_signs():
    """Joint 2's world torque is -u*2 and its world speed -dtheta21 (plant.fivebar): a
    current in drive 2 must accelerate q2 as the same torque on the bare plant's tau2 does."""
    a = _actuated()
    z = a.state()
    z[14:] = [0.0, 1.5]
    tau2 = shaft_torque(1.5, 0.0, a.drives[1][1].params)
    expected = a.plant.derivative(z[:14], np.array([0.0, -tau2]))
    assert np.allclose(a.derivative(z, [0.0, 0.0])[:14], expected, rtol=1e-14, atol=1e-14)


def test_energy_balance_with_kt_equal_ke():
    """With kt = ke the electromechanical conversion is lossless: over a run, the energy the
    supply delivers = resistive + friction losses + magnetic + kinetic energy (no gravity).
    A sign error in the coupling of either joint breaks it."""
    motor = get_motor_preset("motor1")
    a = _actuated(settings=IntegratorSettings(substeps=16), ke=motor.kt, mu=0.0)
    h, steps = 1e-3, 200
    supplied = lost = 0.0
    ke0 = a.plant.kinetic_energy()
    magnetic = lambda: sum(0.5 * d.params.L * d.i ** 2 for _, d in a.drives)   # noqa: E731
    m0 = magnetic()
    for k in range(steps):
        i_ref = (2.0 * np.sin(20 * k * h), -1.5 * np.cos(15 * k * h))
        # trapezoidal sums over sub-intervals of the step: integrate power with the states
        z0 = a.state()
        a.step(i_ref, [d.i for _, d in a.drives], (0.0, 0.0), h)
        z1 = a.state()
        for n, (j, d) in enumerate(a.drives):
            w0 = (z0[10], -z0[12])[j - 1]
            w1 = (z1[10], -z1[12])[j - 1]
            p = d.params
            supplied += 0.5 * h * d.v * (z0[14 + n] + z1[14 + n])
            lost += 0.5 * h * (p.R * (z0[14 + n] ** 2 + z1[14 + n] ** 2) + p.b * (w0 ** 2 + w1 ** 2))
    stored = (a.plant.kinetic_energy() - ke0) + (magnetic() - m0)
    assert supplied > 1e-2                          # the test moved something
    assert abs(supplied - lost - stored) < 1e-3 * supplied


def test_rk4_steps_beyond_the_electrical_pole_are_refused_by_name():
    """Catches an in-plant drive whose RK4 step exceeds its electrical pole's stability limit stepped
    anyway (a diverging current), refused without the numbers and the substeps that would do, or with
    the state changed."""
    a = _actuated(L=1e-5)
    state = a.state()
    with pytest.raises(PlantError, match=r"drive on joint 1: RK4 steps of 0.001 s are unstable.*R h / L = 110.1 > 2.785 "
                                         r"\(L/R = 9.08e-06 s\).*substeps >= 56"):
        a.step((1.0, 1.0), (0.0, 0.0), (0.0, 0.0), 1e-3)
    assert np.array_equal(a.state(), state)


def test_quasi_static_drive_refused():
    """Catches an actuated plant accepting a drive with L = 0 (no armature current state)."""
    sim = PlantSimulator(get_preset("bench"), *START)
    drive = Drive(get_motor_preset("motor2").with_(L=0.0), mode="voltage")
    with pytest.raises(ValueError, match="drive on joint 2: L = 0.0 H has no armature current"):
        ActuatedPlant(sim, [(2, drive)])


# --- the scene --------------------------------------------------------------------------------

def _short(scene, stop):
    return replace(scene, system=replace(scene.system, stop_time=stop))


def test_drives_in_plant_rewires_the_bench():
    """Catches drives_in_plant dropping or miswiring a connection, a parameter or a column."""
    scene = drives_in_plant(get_scene("bench_circle_TCMDx"), substeps=4)
    models = {c.name: c.model for c in scene.system.components}
    assert "drive1" not in models and models["plant"] == "ActuatedFiveBarPlant"
    plant = scene.system.component("plant").parameters
    assert plant["preset1"] == "motor1" and plant["preset2"] == "motor2" and plant["substeps"] == 4
    assert "torque_output1" not in plant and plant["mode"] == "current"
    pairs = {(c.source, c.target) for c in scene.system.connections}
    assert ("ctrl.i_ref1", "plant.i_ref1") in pairs and ("plant.v2", "obs2.v") in pairs
    assert ("obs1.i_hat", "plant.i_hat1") in pairs
    assert scene.columns["i1"] == "plant.i1" and scene.columns["tau2_shaft"] == "plant.tau2"


def test_drives_in_plant_needs_drives():
    """Catches drives_in_plant silently returning a scene that has no drive."""
    with pytest.raises(ValueError, match="no DCMotorDrive to move into the plant"):
        drives_in_plant(get_scene("thesis_sim_circle"))


def test_converges_to_the_monolithic_reference():
    """The reference integrates the same ODE with DOP853 at rtol 1e-10; with the controllers
    sampling identically, RK4 substeps must converge to it at 4th order, far below the
    separate drives' coupling error."""
    base = _short(get_scene("bench_circle_TCMDx"), 0.3)
    reference = reference_run(base)
    errors = {}
    for n in (2, 4, 8):
        result = simulate(drives_in_plant(base, substeps=n).system)
        assert result.completed, result.error
        errors[n] = deviation(result, reference)["max"]
    separate = deviation(simulate(base.system), reference)["max"]
    assert errors[8] < 1e-9 < separate
    assert errors[8] < errors[4] / 8 and errors[4] < errors[2] / 8


def test_fmu_and_inprocess_identical(built_fmus):
    """Catches an ActuatedFiveBarPlant FMU whose rows differ from the in-process run by a bit."""
    fmu_dir = next(iter(built_fmus.values())).parent
    system = drives_in_plant(_short(get_scene("bench_triangle_TCMDx"), 0.1), substeps=2).system
    a = simulate(system, mode="inprocess")
    b = simulate(system, mode="fmu", fmu_dir=fmu_dir)
    assert a.completed and b.completed, (a.error, b.error)
    for signal in system.record:
        assert np.array_equal(a[signal], b[signal]), signal


def test_the_reference_of_an_in_plant_scene_points_to_its_original():
    """Catches the monolithic reference run on a scene whose drives were moved into the plant (it would
    compare the model with itself) instead of pointing to the original scene."""
    from scenarios.reference import ReferenceError

    with pytest.raises(ReferenceError, match="plant is an ActuatedFiveBarPlant: its truth is the reference of the "
                                             "scene before scenarios.scenes.transforms.drives_in_plant"):
        reference_run(drives_in_plant(_short(get_scene("bench_circle_TCMDx"), 0.01)))


# --- the compiled step's report ------------------------------------------------------------------

def test_compiled_report_equals_the_python_checks_and_outputs():
    """plant.fast5r.report must give exactly what PlantSimulator computes in Python for the
    same state: the residual, the singularity measures and every output, the encoders with their
    zero errors (off whole counts, of both signs)."""
    sim = PlantSimulator(get_preset("bench"), *START, IntegratorSettings(project=True),   # Python path
                         encoder_offsets=(2.37e-3, -4.61e-3))
    rng = np.random.default_rng(3)
    for _ in range(20):
        sim.y = sim.y.copy()
        sim.y[7:] += rng.normal(scale=0.2, size=7)
        sim.y[3:7] += rng.normal(scale=1e-4, size=4)        # off the constraints: a residual to report
        out = np.empty(fast5r.REPORT_SIZE)
        fast5r.report(fast5r.pack_params(sim.params), sim.y, sim.count, *sim.encoder_offsets, out)
        report = out.tolist()
        expected = sim.outputs()
        assert report[fast5r.REPORT_FINITE] == 1.0
        assert report[fast5r.REPORT_RESIDUAL] == pytest.approx(expected["residual"], rel=1e-12)
        assert tuple(report[fast5r.REPORT_MEASURES:fast5r.REPORT_MEASURES + 3]) == pytest.approx(
            sim._pose_measures(sim.y), rel=1e-14, abs=1e-15)
        names = ("q1", "q2", "dq1", "dq2", "x", "y", "dx", "dy", "q1_enc", "q2_enc")
        assert report[fast5r.REPORT_OUTPUTS:] == [expected[n] for n in names]
    z = sim.y.copy()
    z[8] = np.nan
    fast5r.report(fast5r.pack_params(sim.params), z, sim.count, 0.0, 0.0, out)
    assert out[fast5r.REPORT_FINITE] == 0.0


@pytest.mark.parametrize("settings", [IntegratorSettings(kernel="general", substeps=16),
                                      IntegratorSettings(method="dopri5", rtol=1e-11, atol=1e-14),
                                      IntegratorSettings(substeps=16, project=True)],
                         ids=["general-rk4", "dopri5", "rk4-project"])
def test_every_integration_path_agrees(settings):
    """The compiled RK4 step (the default path), the Python RK4 of the general kernel, dopri5
    and RK4 with projection integrate the same ODE: 50 steps of a current-driven motion agree."""
    def run(s):
        a = _actuated(settings=s)
        for k in range(50):
            a.step((3.0 * np.sin(30 * k * 1e-3), -2.0), [d.i for _, d in a.drives], (0.0, 0.0), 1e-3)
        return a.state()

    reference = run(IntegratorSettings(substeps=16))
    other = run(settings)
    assert np.hypot(*(other[:2] - reference[:2])) < 1e-10
    assert np.max(np.abs(other[14:] - reference[14:])) < 1e-8
    assert np.hypot(*(reference[:2] - _actuated().plant.y[:2])) > 1e-4      # it moved


def test_a_miswired_drive_is_refused_by_name():
    """The drive's omega read from the other joint: drives_in_plant and the reference refuse it alike."""
    from fmus.cosim.system import Connection
    from scenarios.reference import ReferenceError

    scene = _short(get_scene("bench_circle_TCMDx"), 0.01)
    wrong = tuple(Connection("plant.dq2", c.target) if c.target == "drive1.omega" else c
                  for c in scene.system.connections)
    scene = replace(scene, system=replace(scene.system, connections=wrong))
    with pytest.raises(ValueError, match=r"drive drive1: omega must be plant.dq1 \(got plant.dq2\)"):
        drives_in_plant(scene)
    with pytest.raises(ReferenceError, match=r"drive drive1: omega must be plant.dq1 \(got plant.dq2\)"):
        reference_run(scene)


def _lugre_replay(drive, z, speeds, h):
    """The deflection (1) reaches from z over steps of length h with these speeds held: the
    drive's own LuGre model, its own array (motor.friction.advance)."""
    f = friction.new_lugre(friction.LuGre.of_motor(drive.params))
    for omega in speeds:
        z = friction.advance(f, z, omega, h)[0]
    return z


def test_a_lugre_drive_reads_as_the_drive_inside_the_plant():
    """The bristle deflection has one owner, the drive: after steps of the plant, each drive's
    z is the deflection its speeds drove (1) to, and drive.torque (kt i minus (4) with
    sigma2 = b) is the plant's shaft torque (kt i - b omega minus the bristles' torque)."""
    sim = PlantSimulator(get_preset("bench"), *START, IntegratorSettings())
    a = ActuatedPlant(sim, [(j, Drive(get_motor_preset(f"motor{j}"), friction="lugre")) for j in (1, 2)])
    h, speeds = 1e-3, []
    for k in range(40):
        speeds.append(fivebar.world_rates(a.plant.y[7:]))
        a.step((0.4 * np.sin(60 * k * h), -0.3), a.currents, (0.0, 0.0), h)
    rates = fivebar.world_rates(a.plant.y[7:])
    for (j, d), tau in zip(a.drives, a.shaft_torques()):
        z = _lugre_replay(d, 0.0, [w[j - 1] for w in speeds], h)
        assert abs(z) > 1e-4, "precondition: the bristles deflected"
        assert d.z == z
        assert d.torque(rates[j - 1]) == pytest.approx(tau, rel=1e-12)
    with pytest.raises(ValueError, match="z = 0.001: a drive with friction 'tanh' has no bristle deflection"):
        Drive(get_motor_preset("motor1")).z = 1e-3


def test_a_bad_input_changes_nothing():
    """A NaN at drive 2's input is refused by name before drive 1's controller samples."""
    a = _actuated()
    a.step((1.0, -1.0), (0.2, -0.2), (0.0, 0.0), 1e-3)
    controller = a.drives[0][1].controller
    state, before = a.state(), dict(vars(controller))
    with pytest.raises(ValueError, match=r"input i_ref2 = nan is not finite"):
        a.step((2.0, float("nan")), (0.2, -0.2), (0.0, 0.0), 1e-3)
    assert np.array_equal(a.state(), state) and vars(controller) == before
    a.step((1.0, -1.0), (0.2, -0.2), (0.0, 0.0), 1e-3)            # and it steps on


# --- idle steps: the plant as a model inside a control chain (fmus.systemfmu.cores.ChainCore) --------

def _actuated_slave(mode, **parameters):
    from fmus.cosim.backends import InProcessInstance

    instance = InProcessInstance("ActuatedFiveBarPlant", "plant")
    instance.initialize({"preset": "bench", "x0": START[0], "y0": START[1], "mode": mode, "substeps": 32,
                         **parameters}, 0.0)
    return instance.slave


def test_idle_steps_hold_zero_volts_as_the_real_plant_commanded_zero():
    """ChainCore commands the real plant (voltage mode) 0 V over its first step and makes its
    model idle for that step: the model's idle step must be the real plant's step, bit for bit,
    whatever the model's current references say, so that the chain's prediction stays exact.
    With both armatures shorted the state is the ODE of (5.66) and (4.162) at v = 0
    (scipy's DOP853 of ActuatedPlant.derivative, an integrator independent of the step's
    compiled RK4); the drives' controllers do not sample, and one idle step is all it takes."""
    from scipy.integrate import solve_ivp

    model, plant = _actuated_slave("current"), _actuated_slave("voltage")
    h = 1e-3
    for k in range(30):                                   # a motion with currents to short
        model.i_ref1, model.i_ref2 = 3.0 * np.sin(40 * k * h), -2.0
        model.i_hat1, model.i_hat2 = model.i1, model.i2
        model.do_step(k * h, h)
        plant.v_ref1, plant.v_ref2 = model.v1, model.v2    # the voltages the model's drives applied
        plant.do_step(k * h, h)
    assert np.array_equal(model.actuated.state(), plant.actuated.state())
    z0 = model.actuated.state()
    assert np.min(np.abs(z0[14:])) > 0.1 and abs(model.dq1) > 0.1   # currents and speed to short

    controllers = [d.controller.buf.copy() for _, d in model.actuated.drives]
    model.idle_steps = 1
    model.i_ref1, model.i_ref2 = 5.0, 5.0                 # ignored while idle
    model.do_step(30 * h, h)
    plant.v_ref1 = plant.v_ref2 = 0.0
    plant.do_step(30 * h, h)
    assert model.idle_steps == 0
    assert np.array_equal(model.actuated.state(), plant.actuated.state())
    assert (model.v1, model.v2, model.i1, model.tau2) == (0.0, 0.0, plant.i1, plant.tau2)
    assert all(np.array_equal(d.controller.buf, c) for (_, d), c in zip(model.actuated.drives, controllers))

    exact = solve_ivp(lambda t, z: model.actuated.derivative(z, [0.0, 0.0]), (0.0, h), z0, method="DOP853",
                      rtol=1e-12, atol=1e-14).y[:, -1]
    z1 = model.actuated.state()
    # RK4 at 32 sub-steps (R h / L = 0.05): 5.5e-8 A measured, 1.6e-5 A at 8 sub-steps (the h^4 ratio)
    assert np.max(np.abs(z1[14:] - exact[14:])) < 1e-6 * np.max(np.abs(z0[14:]))
    assert np.max(np.abs(z1[7:14] - exact[7:14])) < 1e-6 * np.max(np.abs(z0[7:14]))
    assert np.max(np.abs(z1[14:] - z0[14:])) > 0.1        # the short changed the currents

    model.i_hat1, model.i_hat2 = model.i1, model.i2
    model.do_step(31 * h, h)                              # idle no more: the controllers sample 5 A
    assert model.v1 > 0.0 and model.v2 > 0.0


def test_a_correction_redoes_the_bristles_from_the_snapshot():
    """A model of the plant corrected to a measurement (fmus.systemfmu.cores.ChainCore) redoes its
    last step from the snapshot taken before it: the drives' deflections too."""
    from plant.correction import corrected_state

    slave, h = _actuated_slave("current", friction1="lugre", friction2="lugre"), 1e-3
    for k in range(30):
        slave.i_ref1, slave.i_ref2 = 0.5 * np.sin(40 * k * h), -0.3
        slave.i_hat1, slave.i_hat2 = slave.i1, slave.i2
        slave.do_step(k * h, h)
    snapshot = slave.snapshot()
    y0, deflections = snapshot[0].copy(), snapshot[3]
    slave.do_step(30 * h, h)
    measured = {"q1": slave.q1 + 1e-4, "q2": slave.q2, "dq1": slave.dq1, "dq2": slave.dq2}
    model = copy.deepcopy(slave.actuated.plant)
    model.y = y0
    start = fivebar.world_rates(corrected_state(model, measured, h)[7:])   # the redo's start speeds
    assert slave.correct(snapshot, measured, h)
    for (j, d), z0 in zip(slave.actuated.drives, deflections):
        assert d.z == _lugre_replay(d, z0, [start[j - 1]], h) != z0


@pytest.mark.parametrize("parameters, name, value, words", [
    ({"friction2": "lugre", "mu_s2": 0.001}, "mu_s2", 0.001,
     "LuGre friction: the break-away torque Fs (mu_s2) = 0.001 must be >= the Coulomb torque Fc (mu2) = 0.0499"),
    ({"friction1": "lugre", "mu1": 0.0}, "mu1", 0.0, "LuGre friction: Fc (mu1) = 0.0 must be > 0"),
    ({"current_noise2": -1.0}, "current_noise2", -1.0, "current_noise2 must be >= 0, got -1.0"),
    ({"friction1": "coulomb"}, "friction1", "coulomb", "friction1 must be one of 'tanh', 'lugre'; got 'coulomb'"),
], ids=["mu_s2", "mu1", "current_noise2", "friction1"])
def test_a_bad_drive_parameter_is_refused_by_its_fmu_name(parameters, name, value, words):
    """The drives' refusals name the FMU's variables (suffix j), as fields and in the message."""
    from fmus.slave.declarations import build_drive
    from motor._checks import BadValue

    slave = _actuated_slave("current", **parameters)
    assert slave.actuated is None and f"initialisation refused: {words}" in slave.error
    with pytest.raises(BadValue) as refusal:
        build_drive(slave, name[-1], mode="current", T=1e-3)
    assert (refusal.value.name, refusal.value.value) == (name, value)



@pytest.mark.parametrize("parameters, name, value, words", [
    ({"J_design2": 0.0}, "J_design2", 0.0, "parameter J_design2 must be > 0, got 0.0"),
    ({"kt1": float("inf")}, "kt1", float("inf"), "parameter kt1 must be a finite number, got inf"),
    ({"omega_eps2": 0.0}, "omega_eps2", 0.0, "parameter omega_eps2 must be > 0, got 0.0"),
    ({"mu_s1": -3.0}, "mu_s1", -3.0, "parameter mu_s1 = -3.0 is negative (use -1 for the preset's value)"),
], ids=["J_design2", "kt1", "omega_eps2", "mu_s1"])
def test_a_bad_motor_override_is_refused_by_its_fmu_name(parameters, name, value, words):
    """A motor parameter the slave overrides (fmus.slave.refusals.with_overrides) is refused by its FMU
    variable, suffix j included, and its value, as fields and in the message: J_design2 is
    MotorParams' J_rotor, kt1 and omega_eps2 its kt and omega_eps; mu_s1 is refused before
    MotorParams sees it."""
    from fmus.slave.declarations import build_drive
    from motor._checks import BadValue

    slave = _actuated_slave("current", **parameters)
    assert slave.actuated is None and f"initialisation refused: {words} (t = 0 s)" in slave.error
    with pytest.raises(BadValue) as refusal:
        build_drive(slave, name[-1], mode="current", T=1e-3)
    assert (refusal.value.name, refusal.value.value, str(refusal.value)) == (name, value, words)


def test_the_fast_plants_derivative_is_the_general_one_and_omega_held_at_the_rates_changes_nothing():
    """ActuatedPlant.derivative through its C kernel (the fast plant, no held speed) is the
    general algorithm's with the motors' equations (the general plant), and the general path
    with the joints' own rates as ``omega_held`` is that too.  Catches the fast path handed
    another array than the voltages (the held speeds: None there)."""
    fast, general = _actuated("fast"), _actuated("general")
    rng = np.random.default_rng(11)
    for _ in range(5):
        z, v = _random_state(fast, rng), rng.normal(scale=10.0, size=2)
        external = rng.normal(scale=0.05, size=2)
        expected = general.derivative(z, v, external)
        scale = np.max(np.abs(expected))
        np.testing.assert_allclose(fast.derivative(z, v, external), expected, rtol=1e-12, atol=1e-12 * scale)
        held = fivebar.world_rates(z[7:14])
        np.testing.assert_allclose(fast.derivative(z, v, external, omega_held=held), expected, rtol=1e-12,
                                   atol=1e-12 * scale)
