"""The thesis' parallel algorithm (5.1-5.77) against an independent Lagrange
formulation, its compiled 5R kernel against the general numpy version, and the
integrated motion against conservation laws and a tight reference."""
import functools
import math
from dataclasses import replace

import numpy as np
import pytest

from plant import ACCURATE, IntegratorSettings, PlantError, PlantSimulator, get_preset
from plant import fast5r, fivebar
from plant.fast5r import FastKernel
from plant.parallel import forward_dynamics, inverse_dynamics, inverse_dynamics_terms, mechanism_state
from tests.support import lagrange5r as ref

PRESETS = ("thesis_sim", "bench")


def variant(preset, balanced=False):
    """The preset with an end-effector mass and in-plane gravity, so every term is exercised;
    ``balanced``: with seed 001's counter-masses (0.4, 0.2) kg instead of the end-effector mass."""
    if balanced:
        return replace(get_preset(preset), gravity=(2.0, -9.81, 0.5)).with_counter_masses(0.4, 0.2)
    return replace(get_preset(preset), m0=0.04, gravity=(2.0, -9.81, 0.5))


def reference_params(params):
    """The plain dict the independent model reads, from the same preset."""
    chains = [dict(l1=c.l1, l2=c.l2, lg1=c.lg1, lg2=c.lg2, m1=c.m1, m2=c.m2, Jz1=c.Jz1, Jz2=c.Jz2,
                   J_rotor=c.J_rotor) for c in (params.chain1, params.chain2)]
    return {"l0": params.l0, "chains": chains, "m0": params.m0, "g": tuple(params.gravity)}


def random_states(params, n, seed):
    """Consistent (q, dq) at random non-singular points with random velocities."""
    rng = np.random.default_rng(seed)
    mech = fivebar.build_mechanism(params)
    states = []
    while len(states) < n:
        x, y = rng.uniform(-0.1, 0.1), rng.uniform(0.08, 0.25)
        try:
            if fivebar.singularity(params, x, y).margin < 0.2:
                continue
        except fivebar.KinematicsError:
            continue
        q = fivebar.thesis_coordinates(params, x, y)
        dq = mechanism_state(mech, q, np.zeros(7)).C @ rng.uniform(-1.0, 1.0, 2)
        states.append((q, dq))
    return mech, states


def world_phi(q, dq):
    """Absolute world link angles and rates from the thesis' q, dq."""
    phi = np.array([q[3], q[3] + q[4], math.pi - q[5], math.pi - q[5] - q[6]])
    dphi = np.array([dq[3], dq[3] + dq[4], -dq[5], -dq[5] - dq[6]])
    return phi, dphi


@pytest.mark.parametrize("preset", PRESETS)
def test_accelerations_equal_the_lagrange_formulation(preset):
    """Catches the plant's constrained forward dynamics (thesis ch. 5) differing from an independent
    Lagrange formulation of the 5R beyond 1e-10."""
    params = variant(preset)
    rp = reference_params(params)
    mech, states = random_states(params, 20, seed=3)
    rng = np.random.default_rng(4)
    for q, dq in states:
        tau = rng.uniform(-0.3, 0.3, 2)
        ddq = forward_dynamics(mech, q, dq, fivebar.thesis_torques(*tau), baumgarte=0.0)
        phi, dphi = world_phi(q, dq)
        ddphi = ref.accelerations(rp, phi, dphi, tau)
        mine = np.array([ddq[3], ddq[3] + ddq[4], -ddq[5], -ddq[5] - ddq[6]])
        np.testing.assert_allclose(mine, ddphi, rtol=1e-10, atol=1e-10 * np.max(np.abs(ddphi)))
        np.testing.assert_allclose(ddq[:2], ref.tip_acceleration(rp, phi, dphi, ddphi),
                                   rtol=1e-10, atol=1e-10 * np.max(np.abs(ddq[:2])))


@pytest.mark.parametrize("balanced", [False, True])
@pytest.mark.parametrize("preset", PRESETS)
def test_fast_kernel_equals_the_general_algorithm(preset, balanced):
    """Catches the 5R fast kernel's derivative or residual (Baumgarte terms included, off the manifold)
    differing from the general algorithm's."""
    params = variant(preset, balanced)
    kernel = FastKernel(params)
    mech, states = random_states(params, 20, seed=5)
    rng = np.random.default_rng(6)
    for q, dq in states:
        # Off the manifold too, so the Baumgarte terms are compared.
        q = q + rng.normal(scale=1e-4, size=7)
        dq = dq + rng.normal(scale=1e-3, size=7)
        u = rng.uniform(-0.3, 0.3, 2)
        general = forward_dynamics(mech, q, dq, u, baumgarte=50.0)
        fast = kernel.derivative(np.concatenate([q, dq]), u, 50.0)[7:]
        np.testing.assert_allclose(fast, general, rtol=1e-11, atol=1e-11 * np.max(np.abs(general)))
        np.testing.assert_allclose(kernel.residual(np.concatenate([q, dq])),
                                   mechanism_state(mech, q, dq).residual, atol=1e-16)


@pytest.mark.parametrize("preset", PRESETS)
def test_inverse_dynamics_inverts_forward_dynamics(preset):
    """Catches inverse dynamics that is not the inverse of forward dynamics, a C matrix outside A's null
    space, or a mass matrix that is not positive definite."""
    params = variant(preset)
    mech, states = random_states(params, 10, seed=7)
    rng = np.random.default_rng(8)
    for q, dq in states:
        u = rng.uniform(-0.3, 0.3, 2)
        ddq = forward_dynamics(mech, q, dq, u, baumgarte=0.0)
        np.testing.assert_allclose(inverse_dynamics(mech, q, dq, ddq[:2]), u, rtol=1e-10, atol=1e-12)
        terms = inverse_dynamics_terms(mech, q, dq)
        st = mechanism_state(mech, q, dq)
        # (5.68): the full acceleration is C ddq# + c and satisfies the constraints.
        np.testing.assert_allclose(st.C @ ddq[:2] + terms.c, ddq, atol=1e-10 * np.max(np.abs(ddq)))
        np.testing.assert_allclose(st.A @ st.C, 0.0, atol=1e-14)
        assert np.all(np.linalg.eigvalsh(terms.M) > 0)


def test_kinetic_energy_is_conserved_without_torque():
    """Catches a plant that gains or loses kinetic energy without torque or gravity."""
    params = get_preset("bench")
    sim = PlantSimulator(params, 0.0, 0.16, ACCURATE, dx0=0.3, dy0=-0.2)
    e0 = sim.kinetic_energy()
    for _ in range(1000):
        sim.step(0.0, 0.0, 1e-3)
    assert abs(sim.kinetic_energy() - e0) / e0 < 1e-9
    assert sim.residual_norm() < 1e-12


def held_with_wobble(out, t):
    """A PD hold at (0, 0.17) with a wobble: keeps the mechanism moving inside the workspace."""
    tau1 = 0.05 * math.sin(7 * t) - 2.0 * (out["q1"] - 0.8658) - 0.05 * out["dq1"]
    tau2 = 0.05 * math.cos(5 * t) - 2.0 * (out["q2"] - 2.2758) - 0.05 * out["dq2"]
    return tau1, tau2


@pytest.mark.parametrize("project", [True, False])
def test_constraint_residual_stays_closed_over_ten_seconds(project):
    """Catches a loop closure that drifts over 10 s of moving (with and without projection) beyond 1e-10."""
    sim = PlantSimulator(get_preset("thesis_sim"), 0.0, 0.17, IntegratorSettings(project=project))
    worst = 0.0
    for k in range(10000):
        sim.step(*held_with_wobble(sim.outputs(), k * 1e-3), 1e-3)
        worst = max(worst, sim.residual_norm())
    assert worst < 1e-10
    assert math.hypot(sim.outputs()["dx"], sim.outputs()["dy"]) > 1e-3   # it did move


def torque_profile(t):
    return 0.06 * math.sin(2 * math.pi * 2.5 * t) + 0.02, -0.05 * math.cos(2 * math.pi * 1.5 * t)


def held_reference(preset, x0, y0, tau, t_end=0.4, dt=1e-3):
    """Tip and actuated angles of the independent model, each torque held over its step.

    The reference restarts at every step (a solver crossing the steps'
    discontinuities would crawl).  Rows: (x, y, q1, q2) at t = dt, 2 dt, ...
    """
    rp = reference_params(get_preset(preset))
    phi = ref.ik(rp, x0, y0)
    q, dq = np.array([phi[0], phi[2]]), np.zeros(2)
    rows = []
    for k in range(round(t_end / dt)):
        held = tau(k * dt)
        _, qs, dqs = ref.integrate(rp, q, dq, lambda t: held, dt)
        q, dq = qs[-1], dqs[-1]
        phi, _ = ref.full_state(rp, q, dq)
        rows.append((*ref.tip(rp, phi), *q))
    return np.array(rows)


@functools.lru_cache(maxsize=None)
def reference_run(preset, x0, y0):
    return held_reference(preset, x0, y0, torque_profile)


def max_deviation(preset, x0, y0, settings):
    expected = reference_run(preset, x0, y0)
    sim = PlantSimulator(get_preset(preset), x0, y0, settings)
    err = 0.0
    for k, (x, y, q1, q2) in enumerate(expected):
        sim.step(*torque_profile(k * 1e-3), 1e-3)
        out = sim.outputs()
        err = max(err, math.hypot(out["x"] - x, out["y"] - y), abs(out["q1"] - q1) * 0.1, abs(out["q2"] - q2) * 0.1)
    assert math.hypot(expected[-1, 0] - expected[0, 0], expected[-1, 1] - expected[0, 1]) > 0.005  # it moved
    return err


@pytest.mark.parametrize("preset, x0, y0", [("thesis_sim", 0.07, 0.17), ("bench", -0.002, 0.108)])
def test_default_and_accurate_settings_against_the_reference(preset, x0, y0):
    """End-effector error (and joint error x 0.1 m) over 0.4 s: <= 1e-6 m at defaults, <= 1e-9 m accurate."""
    assert max_deviation(preset, x0, y0, IntegratorSettings()) < 1e-6
    assert max_deviation(preset, x0, y0, ACCURATE) < 1e-9


def test_bad_input_is_refused_with_name_value_and_time():
    """Catches a plant step that accepts NaN or inf, or changes its state on a refused step."""
    sim = PlantSimulator(get_preset("thesis_sim"), 0.07, 0.17)
    sim.step(0.0, 0.0, 1e-3)
    state = sim.y.copy()
    with pytest.raises(PlantError, match=r"tau2 = nan at t = 0\.001"):
        sim.step(0.0, float("nan"), 1e-3)
    with pytest.raises(PlantError, match=r"tau1 = inf"):
        sim.step(float("inf"), 0.0, 1e-3)
    np.testing.assert_array_equal(sim.y, state)
    with pytest.raises(ValueError, match=r"x0=0\.5.*outside the workspace"):
        PlantSimulator(get_preset("thesis_sim"), 0.5, 0.17)
    with pytest.raises(ValueError, match=r"preset: unknown preset 'nope'"):
        get_preset("nope")
    with pytest.raises(ValueError, match=r"chain1\.m2 must be >= 0, got -0\.1"):
        PlantSimulator(replace(get_preset("thesis_sim"), chain1=replace(get_preset("thesis_sim").chain1, m2=-0.1)),
                       0.07, 0.17)
    with pytest.raises(ValueError, match=r"cannot close the loop"):
        PlantSimulator(replace(get_preset("thesis_sim"), l0=0.3), 0.0, 0.17)


@pytest.mark.parametrize("settings", [IntegratorSettings(kernel="general"), IntegratorSettings(project=True),
                                      IntegratorSettings(kernel="general", project=True)])
def test_a_diverged_step_outside_the_one_call_path_names_the_held_torques(settings):
    """Catches the step of the general kernel or with projection (PlantSimulator.step's Python
    path) that refuses a diverged step without the torques it held (or with another error than
    PlantError), as the one-call C step does, or that moves the state or the time."""
    sim = PlantSimulator(get_preset("bench"), -0.002, 0.108, settings=settings)
    state = sim.y.copy()
    with pytest.raises(PlantError, match=r"^integration diverged in the step from t = 0 s \(tau1 = 10000\.0, "
                                         r"tau2 = -10000\.0 N m held\): loop-closure residual "):
        sim.step(1e4, -1e4, 1e-3)
    np.testing.assert_array_equal(sim.y, state)
    assert sim.time == 0.0


def test_running_into_a_singularity_stops_with_time_and_place():
    """Catches a plant that integrates through a singular pose, or stops without time and place."""
    sim = PlantSimulator(get_preset("thesis_sim"), 0.07, 0.17)
    with pytest.raises(PlantError, match=r"singular pose reached at t = .* at x = .* y = "):
        for _ in range(5000):
            sim.step(0.05, 0.0, 1e-3)
    assert np.all(np.isfinite(sim.y))


def test_compiled_report_measures_are_the_singularity_sines():
    """The step report's pose measures (what stops a run at a singular pose) are |sin| of the
    elbow angles and of the angle between the distal links, as plant.fivebar.singularity
    computes them from the inverse kinematics (002 eq. 1-6)."""
    params = get_preset("bench")
    p = fast5r.pack_params(params)
    _, states = random_states(params, 10, seed=18)
    out = np.empty(fast5r.REPORT_SIZE)
    for q, dq in states:
        fast5r.report(p, np.concatenate([q, dq]), 1e-3, 0.0, 0.0, out)
        s = fivebar.singularity(params, q[0], q[1])
        measures = out[fast5r.REPORT_MEASURES:fast5r.REPORT_MEASURES + 3]
        assert np.allclose(np.abs(measures), np.abs([s.serial1, s.serial2, s.parallel]), rtol=0, atol=1e-12)


@pytest.mark.parametrize("offsets", [(0.0, 0.0), (0.31, -0.17)])
@pytest.mark.parametrize("counts", [7, 4096])
def test_compiled_report_encoders_read_the_nearest_count(counts, offsets):
    """An encoder of N counts per turn with zero error o reads the multiple of 2π/N nearest to
    the actuated angle plus o (inverse kinematics of the pose): |enc - (q + o)| ≤ count/2.
    N = 7 makes a count 0.9 rad, so rounding down or up by half a count cannot pass."""
    bench = get_preset("bench")
    kernel = FastKernel(bench)
    count = 2 * math.pi / counts
    out = np.empty(fast5r.REPORT_SIZE)
    for x, y in ((0.0, 0.108), (0.03, 0.15), (-0.04, 0.2), (0.05, 0.12), (-0.01, 0.17)):
        angles = fivebar.inverse_kinematics(bench, x, y)
        fast5r.report(kernel.p, PlantSimulator(bench, x, y).y, count, *offsets, out)
        enc = out[fast5r.REPORT_OUTPUTS + 8:fast5r.REPORT_OUTPUTS + 10]
        for reading, q, offset in zip(enc, (angles[0], angles[2]), offsets):
            assert abs(reading / count - round(reading / count)) < 1e-9
            assert abs(reading - (q + offset)) <= count / 2 + 1e-12


def test_baumgarte_too_stiff_for_rk4_is_refused_naming_lambda_h():
    """RK4's real stability limit is λh = 2.785 (|1 - z + z²/2 - z³/6 + z⁴/24| = 1); the plant
    refuses the Baumgarte damping λ once λh passes 2, and says which λh it got: λ = 3000 /s
    with two substeps of a 1 ms step is λh = 1.5 (taken), with one it is 3 (refused)."""
    from plant.simulator import BAUMGARTE_RK4_LIMIT

    z = -2.785293563405282
    assert abs(1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24) == pytest.approx(1.0, abs=1e-12)
    assert BAUMGARTE_RK4_LIMIT == 2.0
    bench = get_preset("bench")
    PlantSimulator(bench, 0.0, 0.108, settings=IntegratorSettings(baumgarte=3000.0, substeps=2)).step(0.0, 0.0, 1e-3)
    sim = PlantSimulator(bench, 0.0, 0.108, settings=IntegratorSettings(baumgarte=3000.0, substeps=1))
    with pytest.raises(PlantError, match=r"baumgarte \* h = 3 > 2, RK4 no longer damps"):
        sim.step(0.0, 0.0, 1e-3)


@pytest.mark.parametrize("name", ["rtol", "atol"])
@pytest.mark.parametrize("value", [0.0, -1e-9, float("nan")])
def test_adaptive_tolerances_must_be_positive(name, value):
    """dopri5's error control divides by atol + rtol |y|: a tolerance <= 0 or NaN is refused."""
    with pytest.raises(ValueError, match=rf"{name} must be > 0, got {value!r}"):
        IntegratorSettings(method="dopri5", **{name: value}).validate()


def test_projection_makes_the_link_rates_satisfy_the_velocity_constraints():
    """After ``project`` (Newton on the loop residual (5.18), then dq = C dq#) the state moves
    along the constraint manifold: the residual's time derivative, by finite differences of
    the residual along the state's own rates, is zero for any end-effector velocity."""
    bench = get_preset("bench")
    kernel = FastKernel(bench)
    rng = np.random.default_rng(3)
    res0, res1 = np.empty(6), np.empty(6)
    for x, y in ((0.0, 0.15), (0.03, 0.19), (-0.04, 0.13)):
        state = PlantSimulator(bench, x, y).y.copy()
        state[3:7] += rng.normal(0.0, 1e-4, 4)          # off the manifold
        state[7:9] = rng.normal(0.0, 0.3, 2)            # end-effector velocity [m/s]
        state[10:14] = rng.normal(0.0, 5.0, 4)          # link rates, inconsistent
        z = kernel.project(state)
        eps = 1e-7
        moved = z.copy()
        moved[0:2] += eps * z[7:9]
        moved[3:7] += eps * z[10:14]
        fast5r.residual(kernel.p, z, res0)
        fast5r.residual(kernel.p, moved, res1)
        assert np.max(np.abs(res0)) < 1e-12
        assert np.max(np.abs(res1 - res0)) / eps < 1e-5 * np.max(np.abs(z[7:9]))
