"""Checks of the independent Lagrange reference model of the 5R (tests/support/lagrange5r.py).

The reference is the truth the project's plant is compared against, so it is
itself checked here against a symbolic derivation (sympy.physics.mechanics),
energy and work balances, the world-frame conventions of the brief ../shared/spec/SYSTEM.md §2 and a
tolerance-refinement study of its integrator.
"""

import numpy as np
import pytest
import sympy as sp
from sympy.physics import mechanics as me

from tests.support import lagrange5r as ref


def _bench_with_tip_mass_and_gravity():
    """Bench parameters with every term switched on (tip mass, in-plane gravity)."""
    params = ref.params_bench()
    params["m0"] = 0.05
    params["g"] = (0.5, 0.5, -9.81)
    return params


def _total_energy(params, q, dq):
    phi, dphi = ref.full_state(params, q, dq)
    return ref.kinetic_energy(params, phi, dphi) + ref.potential_energy(params, phi)


# Tolerance: half a unit of the last digit the brief ../shared/spec/SYSTEM.md quotes.
@pytest.mark.parametrize("x, y, q1_deg, q2_deg, tolerance_deg",
                         [(0.0, 0.17, 49.6, 130.4, 0.05), (0.07, 0.17, 24.36, 99.97, 0.005)])
def test_world_frame_working_mode(x, y, q1_deg, q2_deg, tolerance_deg):
    """Catches a reference in another frame or working mode than SYSTEM.md section 2 (elbows outward)."""
    params = ref.params_thesis_sim()
    phi = ref.ik(params, x, y)
    assert np.degrees(phi[0]) == pytest.approx(q1_deg, abs=tolerance_deg)
    assert np.degrees(phi[2]) == pytest.approx(q2_deg, abs=tolerance_deg)
    assert ref.tip(params, phi) == pytest.approx((x, y), abs=1e-15)
    assert np.allclose(ref.constraint(params, phi), 0.0, atol=1e-15)
    elbow1 = np.array([params["l0"], 0.0]) + 0.12 * np.array([np.cos(phi[0]), np.sin(phi[0])])
    elbow2 = np.array([-params["l0"], 0.0]) + 0.12 * np.array([np.cos(phi[2]), np.sin(phi[2])])
    assert elbow1[0] > x > elbow2[0]  # elbows outward
    assert ref.passive_angles(params, phi[0], phi[2]) == pytest.approx((phi[1], phi[3]), abs=1e-13)


def _symbolic_model():
    """Equations of motion and closure of the 5R built with sympy.physics.mechanics.

    Returns numeric functions of (phi, dphi, tau, parameters) for the
    unconstrained mass matrix, the forcing (applied minus velocity terms), the
    closure Jacobian and the closure's acceleration right-hand side.
    """
    angles = me.dynamicsymbols("phi11 phi12 phi21 phi22")
    rates = [angle.diff() for angle in angles]
    tau1, tau2, l0, m0, gx, gy = sp.symbols("tau1 tau2 l0 m0 gx gy")
    chain_symbols = [sp.symbols(f"l1_{k} l2_{k} lg1_{k} lg2_{k} m1_{k} m2_{k} Jz1_{k} Jz2_{k} Jr_{k}")
                     for k in (1, 2)]
    world = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(world, 0)
    gravity = gx * world.x + gy * world.y

    bodies, loads, tips = [], [], []
    for k, (sign, torque) in enumerate(((1, tau1), (-1, tau2))):
        l1, l2, lg1, lg2, m1, m2, jz1, jz2, jr = chain_symbols[k]
        proximal_angle, distal_angle = angles[2 * k], angles[2 * k + 1]
        base = origin.locatenew(f"B{k}", sign * l0 * world.x)
        base.set_vel(world, 0)
        link1 = world.orientnew(f"A{k}", "Axis", (proximal_angle, world.z))
        link2 = world.orientnew(f"C{k}", "Axis", (distal_angle, world.z))
        com1 = base.locatenew(f"G1{k}", lg1 * link1.x)
        com1.v2pt_theory(base, world, link1)
        elbow = base.locatenew(f"E{k}", l1 * link1.x)
        elbow.v2pt_theory(base, world, link1)
        com2 = elbow.locatenew(f"G2{k}", lg2 * link2.x)
        com2.v2pt_theory(elbow, world, link2)
        tip = elbow.locatenew(f"T{k}", l2 * link2.x)
        tip.v2pt_theory(elbow, world, link2)
        bodies += [me.RigidBody(f"L1{k}", com1, link1, m1, (me.inertia(link1, 0, 0, jz1), com1)),
                   me.RigidBody(f"L2{k}", com2, link2, m2, (me.inertia(link2, 0, 0, jz2), com2)),
                   me.RigidBody(f"R{k}", base, link1, 0, (me.inertia(link1, 0, 0, jr), base))]
        loads += [(com1, m1 * gravity), (com2, m2 * gravity), (link1, torque * world.z)]
        tips.append(tip)
    bodies.append(me.Particle("P", tips[0], m0))
    loads.append((tips[0], m0 * gravity))

    lagrangian = me.Lagrangian(world, *bodies)
    method = me.LagrangesMethod(lagrangian, angles, forcelist=loads, frame=world)
    method.form_lagranges_equations()

    gap = tips[0].pos_from(origin) - tips[1].pos_from(origin)
    closure = sp.Matrix([gap.dot(world.x), gap.dot(world.y)])
    closure_jacobian = closure.jacobian(angles)
    closure_rhs = -(closure_jacobian.diff(me.dynamicsymbols._t) * sp.Matrix(rates))

    state = sp.symbols("p11 p12 p21 p22 w11 w12 w21 w22")
    substitution = dict(zip(angles + rates, state))
    arguments = [state, (tau1, tau2), (l0, m0, gx, gy), chain_symbols]

    def numeric(expression):
        return sp.lambdify(arguments, sp.Matrix(expression).subs(substitution), "numpy")

    return (numeric(method.mass_matrix), numeric(method.forcing),
            numeric(closure_jacobian), numeric(closure_rhs))


def test_sympy_mechanics_cross_check():
    """Catches a wrong mass matrix, forcing or constraint Jacobian of the reference (sympy.physics.mechanics)."""
    params = _bench_with_tip_mass_and_gravity()
    mass_fn, forcing_fn, jacobian_fn, rhs_fn = _symbolic_model()
    chain_values = [[c["l1"], c["l2"], c["lg1"], c["lg2"], c["m1"], c["m2"], c["Jz1"], c["Jz2"],
                     c["J_rotor"]] for c in params["chains"]]
    scalar_values = (params["l0"], params["m0"], params["g"][0], params["g"][1])
    rng = np.random.default_rng(5)
    phi = np.array(ref.ik(params, 0.03, 0.2))
    for _ in range(3):
        # Any 4 angles and rates: the unconstrained terms must agree everywhere.
        dphi = rng.uniform(-3.0, 3.0, 4)
        tau = rng.uniform(-0.2, 0.2, 2)
        arguments = (np.concatenate([phi, dphi]), tau, scalar_values, chain_values)
        mass = np.array(mass_fn(*arguments), dtype=float)
        forcing = np.array(forcing_fn(*arguments), dtype=float).ravel()
        jacobian = np.array(jacobian_fn(*arguments), dtype=float)
        closure_rhs = np.array(rhs_fn(*arguments), dtype=float).ravel()

        applied = ref.gravity_forces(params, phi) + np.array([tau[0], 0.0, tau[1], 0.0])
        assert np.allclose(ref.mass_matrix(params, phi), mass, rtol=1e-13, atol=1e-18)
        assert np.allclose(applied - ref.velocity_forces(params, phi, dphi), forcing,
                           rtol=1e-12, atol=1e-15)
        assert np.allclose(ref.constraint_jacobian(params, phi), jacobian, rtol=1e-13, atol=1e-16)
        assert np.allclose(ref.constraint_acceleration_rhs(params, phi, dphi), closure_rhs,
                           rtol=1e-12, atol=1e-15)
        phi = phi + rng.uniform(-0.5, 0.5, 4)

    # Constrained accelerations from the symbolic blocks at a consistent state.
    phi, dphi = ref.full_state(params, (phi[0], phi[2]), (1.3, -0.7))
    tau = np.array([0.1, -0.05])
    arguments = (np.concatenate([phi, dphi]), tau, scalar_values, chain_values)
    jacobian = np.array(jacobian_fn(*arguments), dtype=float)
    augmented = np.block([[np.array(mass_fn(*arguments), dtype=float), jacobian.T],
                          [jacobian, np.zeros((2, 2))]])
    rhs = np.concatenate([np.array(forcing_fn(*arguments), dtype=float).ravel(),
                          np.array(rhs_fn(*arguments), dtype=float).ravel()])
    symbolic_ddphi = np.linalg.solve(augmented, rhs)[:4]
    assert np.allclose(ref.accelerations(params, phi, dphi, tau), symbolic_ddphi, rtol=1e-11)


def test_accelerations_keep_tips_together():
    """Catches reference accelerations that violate the loop closure at acceleration or velocity level."""
    params = _bench_with_tip_mass_and_gravity()
    phi, dphi = ref.full_state(params, ref.ik(params, -0.04, 0.15)[::2], (2.0, 1.5))
    ddphi = ref.accelerations(params, phi, dphi, (0.2, -0.1))
    closure_residual = (ref.constraint_jacobian(params, phi) @ ddphi
                        - ref.constraint_acceleration_rhs(params, phi, dphi))
    assert np.allclose(closure_residual, 0.0, atol=1e-12)
    assert np.allclose(ref.constraint_jacobian(params, phi) @ dphi, 0.0, atol=1e-15)


@pytest.mark.parametrize("gravity, dq0", [((0.0, 0.0, 0.0), (0.3, -0.3)),
                                          ((0.5, 0.5, -9.81), (0.3, -0.3))])
def test_energy_conserved_without_torque(gravity, dq0):
    """Catches a reference that gains or loses energy without torque (any gravity)."""
    params = ref.params_bench()
    params["m0"] = 0.05
    params["g"] = gravity
    phi = ref.ik(params, 0.0, 0.17)
    _, q, dq = ref.integrate(params, (phi[0], phi[2]), dq0, lambda t: (0.0, 0.0), 1.0)
    energies = np.array([_total_energy(params, q_k, dq_k) for q_k, dq_k in zip(q, dq)])
    kinetic_scale = max(ref.kinetic_energy(params, *ref.full_state(params, q_k, dq_k))
                        for q_k, dq_k in zip(q, dq))
    # Relative to the kinetic energy: the potential's datum is arbitrary.
    assert np.max(np.abs(energies - energies[0])) / kinetic_scale <= 1e-9
    assert np.ptp(q[:, 0]) > 0.2  # the mechanism really moved


def test_work_of_constant_torques_equals_energy_gain():
    """Catches a reference whose energy gain is not the work of the torques (a wrong sign or scale)."""
    params = ref.params_bench()
    tau = (0.03, -0.02)
    phi = ref.ik(params, 0.0, 0.17)
    q0 = np.array([phi[0], phi[2]])
    _, q, dq = ref.integrate(params, q0, (0.0, 0.0), lambda t: tau, 0.3)
    work = tau[0] * (q[-1, 0] - q0[0]) + tau[1] * (q[-1, 1] - q0[1])
    assert work > 0.0
    assert _total_energy(params, q[-1], dq[-1]) == pytest.approx(work, rel=1e-10)


def test_tolerance_refinement_reaches_1e_11_m():
    """Catches a reference integrator whose default tolerance is coarser than 1e-11 m."""
    params = ref.params_bench()

    def torques(t):
        return 0.05 * np.sin(2 * np.pi * t) + 0.02, -0.03 * np.cos(3 * t)

    t_eval = np.linspace(0.0, 0.4, 41)
    _, x, y, _, _ = ref.simulate(params, 0.0, 0.17, torques, 0.4, t_eval=t_eval)
    _, x_fine, y_fine, _, _ = ref.simulate(params, 0.0, 0.17, torques, 0.4,
                                           rtol=1e-13, atol=1e-15, t_eval=t_eval)
    assert np.hypot(x[-1] - x[0], y[-1] - y[0]) > 0.05  # large motion, not a trivial check
    assert np.max(np.hypot(x - x_fine, y - y_fine)) < 1e-11


def test_parallel_singularity_is_reported():
    """Catches a reference that returns rates at a parallel singularity instead of refusing."""
    params = ref.params_thesis_sim()
    phi = ref.ik(params, 0.0, 0.17)
    with pytest.raises(ValueError, match="singularity"):
        ref.passive_rates(params, (phi[0], 1.0, phi[2], 1.0), 0.1, 0.1)
