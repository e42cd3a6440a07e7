"""Independent reference dynamics of the planar 5R (five-bar) parallel robot.

Written from scratch to check the project's plant (thesis ch. 4-5 algorithm),
so it shares no code and no formulation with ``plant/``: Lagrange multipliers
on the ABSOLUTE world angles of the four links instead of coupled serial
chains with architecture matrices.

Model
-----
World frame of the brief ../shared/spec/SYSTEM.md §2: x right, y up, origin midway between the bases.
Chain 1 (index 0) has its base joint at (+l0, 0), chain 2 (index 1) at
(-l0, 0). Generalized coordinates, all measured counter-clockwise from +x::

    phi = (phi11, phi12, phi21, phi22)

``phi11 = q1`` and ``phi21 = q2`` are the actuated angles, ``phi12`` and
``phi22`` the absolute angles of the distal links (the passive elbow joints
are unactuated). Each link is a planar rigid body of mass ``m``, centre-of-mass
inertia ``Jz`` and centre of mass at ``lg`` from its proximal joint along the
link. The rotor inertia ``J_rotor`` of a chain turns with its first link. The
end-effector point mass ``m0`` sits on the common tip (attached to chain 1's
distal link; the closure constraint makes the choice immaterial). A chain may
carry point masses (counter-masses, seed 001 (55)): optional keys ``M1`` at
the signed distance ``L1`` from the base joint along link 1 and ``M2`` at
``L2`` from the elbow along link 2 (negative: behind the joint); each is a
particle of its own in the Lagrangian, moving with its link. Gravity is
the 3-vector ``g`` in the world frame; only its in-plane part does work.
Torques ``tau = (tau1, tau2)`` act between the ground and links 11 and 21,
counter-clockwise positive.

The closure ``Phi(phi) = tip1(phi) - tip2(phi) = 0`` gives the index-1 DAE::

    [ M        Phi_phi^T ] [ ddphi  ]   [ Q - c                ]
    [ Phi_phi  0         ] [ lambda ] = [ -d/dt(Phi_phi) dphi ]

The integrator (:func:`simulate`, :func:`integrate`) carries only the two
independent coordinates (q1, q2) and their rates. At every evaluation the
passive angles are recovered in closed form (circle intersection) and the
passive rates from the velocity constraint, so the closure holds to round-off
without any stabilisation term that could bias the result.

API
---
params_thesis_sim(), params_bench() -> dict
    ``{"l0", "chains": [chain1, chain2], "m0", "g"}`` with each chain a dict
    ``{"l1", "l2", "lg1", "lg2", "m1", "m2", "Jz1", "Jz2", "J_rotor"}``.
ik(params, x, y) -> (phi11, phi12, phi21, phi22)
    Inverse kinematics in the "elbows outward" working mode.
tip(params, phi) -> (x, y)
passive_angles(params, q1, q2) -> (phi12, phi22)
    Direct kinematics of the passive angles in the assembly mode of the
    working region (tip above the line through the two elbows).
passive_rates(params, phi, dq1, dq2) -> (dphi12, dphi22)
mass_matrix(params, phi), velocity_forces(params, phi, dphi),
gravity_forces(params, phi), constraint(params, phi),
constraint_jacobian(params, phi), constraint_acceleration_rhs(params, phi, dphi)
    The blocks of the DAE above (``c`` = velocity_forces, ``Q`` = gravity
    forces plus the joint torques).
accelerations(params, phi, dphi, tau) -> ddphi
constraint_forces(params, phi, dphi, tau) -> lambda
tip_acceleration(params, phi, dphi, ddphi) -> (ddx, ddy)
kinetic_energy(params, phi, dphi), potential_energy(params, phi)
integrate(params, q0, dq0, tau_fn, t_end, rtol, atol, t_eval) -> (t, q, dq)
    Reduced ODE in (q1, q2) from any consistent initial state.
simulate(params, x0, y0, tau_fn, t_end, rtol=1e-12, atol=1e-14, t_eval=None)
    -> (t, x, y, q1, q2), starting at rest at (x0, y0); ``tau_fn(t)`` returns
    ``(tau1, tau2)``.
"""

import numpy as np
from scipy.integrate import solve_ivp

#: Smallest |sin| of the angle between the distal links accepted as regular.
PARALLEL_SINGULARITY_SINE = 1e-4


def params_thesis_sim():
    """Return the simulation parameters of thesis Table 3 (both chains equal).

    Returns
    -------
    dict
        Parameter dictionary described in the module docstring.
    """
    chain = {"l1": 0.120, "l2": 0.150, "lg1": 0.060, "lg2": 0.075,
             "m1": 0.143, "m2": 0.171, "Jz1": 1.716e-4, "Jz2": 3.206e-4,
             "J_rotor": 0.0}
    return {"l0": 0.050, "chains": [dict(chain), dict(chain)], "m0": 0.0,
            "g": (0.0, 0.0, 0.0)}


def params_bench():
    """Return the bench parameters of thesis Tables 4-5 with the motor rotor inertias.

    Returns
    -------
    dict
        Parameter dictionary described in the module docstring.
    """
    chain1 = {"l1": 0.120, "l2": 0.160, "lg1": 0.060, "lg2": 0.078,
              "m1": 0.062, "m2": 0.124, "Jz1": 1.073e-4, "Jz2": 4.380e-4,
              "J_rotor": 1.469e-4}
    chain2 = {"l1": 0.120, "l2": 0.160, "lg1": 0.060, "lg2": 0.058,
              "m1": 0.062, "m2": 0.097, "Jz1": 2.960e-4, "Jz2": 9.800e-4,
              "J_rotor": 1.887e-4}
    return {"l0": 0.050, "chains": [chain1, chain2], "m0": 0.0,
            "g": (0.0, 0.0, 0.0)}


def _unit(angle):
    return np.array([np.cos(angle), np.sin(angle)])


def _unit_perp(angle):
    """Derivative of the unit vector with respect to its angle."""
    return np.array([-np.sin(angle), np.cos(angle)])


def _base(params, chain_index):
    return np.array([params["l0"] if chain_index == 0 else -params["l0"], 0.0])


def _tip_mass(params, chain_index):
    """Tip point mass carried by this chain's distal link (all of it on chain 1)."""
    return params["m0"] if chain_index == 0 else 0.0


def _point_masses(chain):
    """(M1, L1, M2, L2): the chain's point masses and where they sit (0 when absent)."""
    return chain.get("M1", 0.0), chain.get("L1", 0.0), chain.get("M2", 0.0), chain.get("L2", 0.0)


def _chain_angles(phi, chain_index):
    return phi[2 * chain_index], phi[2 * chain_index + 1]


def ik(params, x, y):
    """Inverse kinematics in the "elbows outward" working mode.

    Parameters
    ----------
    params : dict
        Robot parameters.
    x, y : float
        End-effector position in the world frame [m].

    Returns
    -------
    tuple of float
        ``(phi11, phi12, phi21, phi22)`` absolute link angles [rad].

    Raises
    ------
    ValueError
        If the point is out of reach of a chain.
    """
    target = np.array([x, y], dtype=float)
    angles = []
    for chain_index, chain in enumerate(params["chains"]):
        base_to_tip = target - _base(params, chain_index)
        distance = np.hypot(*base_to_tip)
        cos_base = ((chain["l1"] ** 2 + distance ** 2 - chain["l2"] ** 2)
                    / (2.0 * chain["l1"] * distance))
        if abs(cos_base) > 1.0:
            raise ValueError(f"point ({x}, {y}) out of reach of chain {chain_index + 1}")
        line_angle = np.arctan2(base_to_tip[1], base_to_tip[0])
        # Chain 1's elbow lies clockwise of the base-tip line (on its right),
        # chain 2's counter-clockwise (on its left).
        offset = np.arccos(cos_base)
        proximal = line_angle - offset if chain_index == 0 else line_angle + offset
        elbow = _base(params, chain_index) + chain["l1"] * _unit(proximal)
        distal = np.arctan2(target[1] - elbow[1], target[0] - elbow[0])
        angles += [proximal, distal]
    return tuple(float(a) for a in angles)


def _chain_tip(params, phi, chain_index):
    chain = params["chains"][chain_index]
    proximal, distal = _chain_angles(phi, chain_index)
    return (_base(params, chain_index) + chain["l1"] * _unit(proximal)
            + chain["l2"] * _unit(distal))


def tip(params, phi):
    """End-effector position reached through chain 1.

    Parameters
    ----------
    params : dict
        Robot parameters.
    phi : array_like, shape (4,)
        Absolute link angles ``(phi11, phi12, phi21, phi22)`` [rad].

    Returns
    -------
    tuple of float
        ``(x, y)`` [m].
    """
    position = _chain_tip(params, np.asarray(phi, dtype=float), 0)
    return float(position[0]), float(position[1])


def passive_angles(params, q1, q2):
    """Absolute angles of the distal links for given actuated angles.

    The tip is the intersection of the circles of radius l2 about the two
    elbows lying to the right of the vector from elbow 1 to elbow 2 (above the
    elbows in the working region).

    Parameters
    ----------
    params : dict
        Robot parameters.
    q1, q2 : float
        Actuated angles [rad].

    Returns
    -------
    tuple of float
        ``(phi12, phi22)`` [rad].

    Raises
    ------
    ValueError
        If the distal links cannot close (configuration not assemblable).
    """
    chain1, chain2 = params["chains"]
    elbow1 = _base(params, 0) + chain1["l1"] * _unit(q1)
    elbow2 = _base(params, 1) + chain2["l1"] * _unit(q2)
    elbow_gap = elbow2 - elbow1
    distance = np.hypot(*elbow_gap)
    along = (distance ** 2 + chain1["l2"] ** 2 - chain2["l2"] ** 2) / (2.0 * distance)
    across_squared = chain1["l2"] ** 2 - along ** 2
    if across_squared < 0.0:
        raise ValueError("distal links cannot close: configuration not assemblable")
    direction = elbow_gap / distance
    right_normal = np.array([direction[1], -direction[0]])
    tip_position = elbow1 + along * direction + np.sqrt(across_squared) * right_normal
    distal1 = tip_position - elbow1
    distal2 = tip_position - elbow2
    return float(np.arctan2(distal1[1], distal1[0])), float(np.arctan2(distal2[1], distal2[0]))


def constraint(params, phi):
    """Closure residual ``tip1 - tip2`` [m], shape (2,)."""
    phi = np.asarray(phi, dtype=float)
    return _chain_tip(params, phi, 0) - _chain_tip(params, phi, 1)


def constraint_jacobian(params, phi):
    """Jacobian of :func:`constraint` with respect to ``phi``, shape (2, 4)."""
    phi = np.asarray(phi, dtype=float)
    columns = []
    for chain_index, sign in ((0, 1.0), (1, -1.0)):
        chain = params["chains"][chain_index]
        proximal, distal = _chain_angles(phi, chain_index)
        columns += [sign * chain["l1"] * _unit_perp(proximal),
                    sign * chain["l2"] * _unit_perp(distal)]
    return np.column_stack(columns)


def constraint_acceleration_rhs(params, phi, dphi):
    """Right-hand side ``-d/dt(Phi_phi) dphi`` of the acceleration-level closure, shape (2,)."""
    phi = np.asarray(phi, dtype=float)
    dphi = np.asarray(dphi, dtype=float)
    rhs = np.zeros(2)
    for chain_index, sign in ((0, 1.0), (1, -1.0)):
        chain = params["chains"][chain_index]
        proximal, distal = _chain_angles(phi, chain_index)
        rate_proximal, rate_distal = _chain_angles(dphi, chain_index)
        rhs += sign * (chain["l1"] * rate_proximal ** 2 * _unit(proximal)
                       + chain["l2"] * rate_distal ** 2 * _unit(distal))
    return rhs


def passive_rates(params, phi, dq1, dq2):
    """Rates of the distal angles that keep the tips together.

    Parameters
    ----------
    params : dict
        Robot parameters.
    phi : array_like, shape (4,)
        Consistent absolute link angles [rad].
    dq1, dq2 : float
        Actuated rates [rad/s].

    Returns
    -------
    tuple of float
        ``(dphi12, dphi22)`` [rad/s].

    Raises
    ------
    ValueError
        Within ``PARALLEL_SINGULARITY_SINE`` of a parallel singularity, where
        the rates and the accelerations are unbounded; raising there stops an
        integration instead of letting the step size collapse.
    """
    if abs(np.sin(phi[3] - phi[1])) < PARALLEL_SINGULARITY_SINE:
        raise ValueError("distal links aligned: parallel (type-2) singularity")
    jacobian = constraint_jacobian(params, phi)
    passive = jacobian[:, [1, 3]]
    active = jacobian[:, [0, 2]]
    rates = np.linalg.solve(passive, -active @ np.array([dq1, dq2]))
    return float(rates[0]), float(rates[1])


def _chain_inertia_terms(params, chain_index):
    """Constant coefficients of one chain's 2x2 mass block.

    Returns ``(proximal, distal, coupling)`` so that the block is
    ``[[proximal, coupling cos(d)], [coupling cos(d), distal]]`` with
    ``d = phi_distal - phi_proximal``.
    """
    chain = params["chains"][chain_index]
    tip_mass = _tip_mass(params, chain_index)
    M1, L1, M2, L2 = _point_masses(chain)
    # A particle at r along link 1 contributes m r^2 dphi11^2 / 2; on link 2 its velocity
    # is l1 dphi11 e_perp(phi11) + r dphi12 e_perp(phi12).
    proximal = (chain["Jz1"] + chain["m1"] * chain["lg1"] ** 2 + chain["J_rotor"] + M1 * L1 ** 2
                + (chain["m2"] + tip_mass + M2) * chain["l1"] ** 2)
    distal = chain["Jz2"] + chain["m2"] * chain["lg2"] ** 2 + tip_mass * chain["l2"] ** 2 + M2 * L2 ** 2
    coupling = chain["l1"] * (chain["m2"] * chain["lg2"] + tip_mass * chain["l2"] + M2 * L2)
    return proximal, distal, coupling


def mass_matrix(params, phi):
    """Mass matrix of the unconstrained 4-link system, shape (4, 4), block diagonal per chain."""
    phi = np.asarray(phi, dtype=float)
    mass = np.zeros((4, 4))
    for chain_index in (0, 1):
        proximal, distal, coupling = _chain_inertia_terms(params, chain_index)
        angle_proximal, angle_distal = _chain_angles(phi, chain_index)
        off_diagonal = coupling * np.cos(angle_distal - angle_proximal)
        block = slice(2 * chain_index, 2 * chain_index + 2)
        mass[block, block] = [[proximal, off_diagonal], [off_diagonal, distal]]
    return mass


def velocity_forces(params, phi, dphi):
    """Centripetal/Coriolis vector ``c`` (left-hand side of the equations of motion), shape (4,)."""
    phi = np.asarray(phi, dtype=float)
    dphi = np.asarray(dphi, dtype=float)
    forces = np.zeros(4)
    for chain_index in (0, 1):
        _, _, coupling = _chain_inertia_terms(params, chain_index)
        angle_proximal, angle_distal = _chain_angles(phi, chain_index)
        rate_proximal, rate_distal = _chain_angles(dphi, chain_index)
        scaled_sine = coupling * np.sin(angle_distal - angle_proximal)
        forces[2 * chain_index] = -scaled_sine * rate_distal ** 2
        forces[2 * chain_index + 1] = scaled_sine * rate_proximal ** 2
    return forces


def gravity_forces(params, phi):
    """Generalized gravity forces ``-dV/dphi`` [N m], shape (4,)."""
    phi = np.asarray(phi, dtype=float)
    gravity = np.asarray(params["g"], dtype=float)[:2]
    forces = np.zeros(4)
    for chain_index in (0, 1):
        chain = params["chains"][chain_index]
        tip_mass = _tip_mass(params, chain_index)
        angle_proximal, angle_distal = _chain_angles(phi, chain_index)
        M1, L1, M2, L2 = _point_masses(chain)
        # Moment arm of the weight of everything a link carries about its joint.
        proximal_moment = (chain["m1"] * chain["lg1"] + M1 * L1
                           + (chain["m2"] + tip_mass + M2) * chain["l1"])
        distal_moment = chain["m2"] * chain["lg2"] + tip_mass * chain["l2"] + M2 * L2
        forces[2 * chain_index] = proximal_moment * gravity @ _unit_perp(angle_proximal)
        forces[2 * chain_index + 1] = distal_moment * gravity @ _unit_perp(angle_distal)
    return forces


def _solve_dae(params, phi, dphi, tau):
    """Solve the augmented system for ``(ddphi, lambda)``."""
    phi = np.asarray(phi, dtype=float)
    dphi = np.asarray(dphi, dtype=float)
    jacobian = constraint_jacobian(params, phi)
    applied = gravity_forces(params, phi)
    applied[0] += tau[0]
    applied[2] += tau[1]
    augmented = np.zeros((6, 6))
    augmented[:4, :4] = mass_matrix(params, phi)
    augmented[:4, 4:] = jacobian.T
    augmented[4:, :4] = jacobian
    rhs = np.concatenate([applied - velocity_forces(params, phi, dphi),
                          constraint_acceleration_rhs(params, phi, dphi)])
    solution = np.linalg.solve(augmented, rhs)
    return solution[:4], solution[4:]


def accelerations(params, phi, dphi, tau):
    """Absolute angular accelerations from the constrained equations of motion.

    Parameters
    ----------
    params : dict
        Robot parameters.
    phi, dphi : array_like, shape (4,)
        Consistent absolute link angles [rad] and rates [rad/s].
    tau : array_like, shape (2,)
        Actuator torques ``(tau1, tau2)`` [N m], counter-clockwise positive.

    Returns
    -------
    numpy.ndarray, shape (4,)
        ``ddphi`` [rad/s^2].
    """
    return _solve_dae(params, phi, dphi, tau)[0]


def constraint_forces(params, phi, dphi, tau):
    """Lagrange multipliers of the closure (the force chain 2 exerts on chain 1's tip is ``-lambda``) [N]."""
    return _solve_dae(params, phi, dphi, tau)[1]


def tip_acceleration(params, phi, dphi, ddphi):
    """End-effector acceleration reached through chain 1.

    Parameters
    ----------
    params : dict
        Robot parameters.
    phi, dphi, ddphi : array_like, shape (4,)
        Absolute link angles, rates and accelerations.

    Returns
    -------
    tuple of float
        ``(ddx, ddy)`` [m/s^2].
    """
    chain = params["chains"][0]
    acceleration = np.zeros(2)
    for length, angle, rate, rate_dot in ((chain["l1"], phi[0], dphi[0], ddphi[0]),
                                          (chain["l2"], phi[1], dphi[1], ddphi[1])):
        acceleration += length * (rate_dot * _unit_perp(angle) - rate ** 2 * _unit(angle))
    return float(acceleration[0]), float(acceleration[1])


def kinetic_energy(params, phi, dphi):
    """Kinetic energy of links, rotors and tip mass [J]."""
    dphi = np.asarray(dphi, dtype=float)
    return float(0.5 * dphi @ mass_matrix(params, phi) @ dphi)


def potential_energy(params, phi):
    """Gravitational potential energy ``-sum m g . r_com`` [J], zero with both links along +x at the base."""
    phi = np.asarray(phi, dtype=float)
    gravity = np.asarray(params["g"], dtype=float)[:2]
    energy = 0.0
    for chain_index in (0, 1):
        chain = params["chains"][chain_index]
        angle_proximal, angle_distal = _chain_angles(phi, chain_index)
        base = _base(params, chain_index)
        elbow = base + chain["l1"] * _unit(angle_proximal)
        M1, L1, M2, L2 = _point_masses(chain)
        weighted_positions = (
            chain["m1"] * (base + chain["lg1"] * _unit(angle_proximal))
            + chain["m2"] * (elbow + chain["lg2"] * _unit(angle_distal))
            + _tip_mass(params, chain_index) * (elbow + chain["l2"] * _unit(angle_distal))
            + M1 * (base + L1 * _unit(angle_proximal)) + M2 * (elbow + L2 * _unit(angle_distal)))
        energy -= gravity @ weighted_positions
    return float(energy)


def full_state(params, q, dq):
    """Absolute angles and rates of all links from the actuated ones.

    Parameters
    ----------
    params : dict
        Robot parameters.
    q, dq : array_like, shape (2,)
        Actuated angles [rad] and rates [rad/s].

    Returns
    -------
    phi, dphi : numpy.ndarray, shape (4,)
    """
    phi12, phi22 = passive_angles(params, q[0], q[1])
    phi = np.array([q[0], phi12, q[1], phi22])
    dphi12, dphi22 = passive_rates(params, phi, dq[0], dq[1])
    return phi, np.array([dq[0], dphi12, dq[1], dphi22])


def integrate(params, q0, dq0, tau_fn, t_end, rtol=1e-12, atol=1e-14, t_eval=None):
    """Integrate the reduced ODE in the actuated coordinates with DOP853.

    Parameters
    ----------
    params : dict
        Robot parameters.
    q0, dq0 : array_like, shape (2,)
        Initial actuated angles [rad] and rates [rad/s].
    tau_fn : callable
        ``tau_fn(t) -> (tau1, tau2)`` [N m].
    t_end : float
        Final time [s].
    rtol, atol : float
        Tolerances of :func:`scipy.integrate.solve_ivp`.
    t_eval : array_like, optional
        Output times; the solver's own steps when omitted.

    Returns
    -------
    t : numpy.ndarray, shape (n,)
    q, dq : numpy.ndarray, shape (n, 2)
    """
    def rhs(t, state):
        phi, dphi = full_state(params, state[:2], state[2:])
        ddphi = accelerations(params, phi, dphi, tau_fn(t))
        return [state[2], state[3], ddphi[0], ddphi[2]]

    initial_state = np.concatenate([np.asarray(q0, float), np.asarray(dq0, float)])
    solution = solve_ivp(rhs, (0.0, t_end), initial_state, method="DOP853",
                         rtol=rtol, atol=atol, t_eval=t_eval)
    if not solution.success:
        raise RuntimeError(f"integration failed: {solution.message}")
    return solution.t, solution.y[:2].T, solution.y[2:].T


def simulate(params, x0, y0, tau_fn, t_end, rtol=1e-12, atol=1e-14, t_eval=None):
    """Simulate the robot from rest at an end-effector position.

    Parameters
    ----------
    params : dict
        Robot parameters.
    x0, y0 : float
        Initial end-effector position [m]; the working mode fixes the angles.
    tau_fn : callable
        ``tau_fn(t) -> (tau1, tau2)`` [N m].
    t_end : float
        Final time [s].
    rtol, atol : float
        Tolerances of the DOP853 integrator.
    t_eval : array_like, optional
        Output times; the solver's own steps when omitted.

    Returns
    -------
    t, x, y, q1, q2 : numpy.ndarray, shape (n,)
        Time [s], end-effector position [m] and actuated angles [rad].
    """
    phi11, _, phi21, _ = ik(params, x0, y0)
    t, q, _ = integrate(params, (phi11, phi21), (0.0, 0.0), tau_fn, t_end,
                        rtol=rtol, atol=atol, t_eval=t_eval)
    tips = []
    for q1, q2 in q:
        phi12, phi22 = passive_angles(params, q1, q2)
        tips.append(tip(params, (q1, phi12, q2, phi22)))
    tips = np.array(tips)
    return t, tips[:, 0], tips[:, 1], q[:, 0], q[:, 1]
