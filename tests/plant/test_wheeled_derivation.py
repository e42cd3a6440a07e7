"""The wheeled pendulum's model against an independent derivation (sympy).

The oracle imports no model code and uses another formulation: full coordinates
q = (x, y, phi, psi, theta_l, theta_r) with the three rolling constraints (no lateral slip,
each wheel rolling) enforced by Lagrange multipliers, the accelerations from the KKT system

    [M  A^T] [q'' ]   [Q - h      ]
    [A  0  ] [-lam] = [-A' q'     ]

at random states.  Its kinetic energy is built from the positions of the wheel centres and
the body's centre of mass (seed 000 (3), (5)) and the rotational energies of (9), the
seed's modelling assumptions.  The substituted Lagrangian of the seed (13) is derived from
the same positions, to check the two nonholonomic terms symbolically.
"""
from __future__ import annotations

import functools

import numpy as np
import pytest

pytestmark = [pytest.mark.slow]

sp = pytest.importorskip("sympy")

t = sp.Symbol("t")
g, m, R, Jw, Mb, W, L, Jpsi, Jphi = sp.symbols("g m R J_w M W L J_psi J_phi", positive=True)
x, y, phi, psi, thl, thr = (sp.Function(n)(t) for n in ("x", "y", "phi", "psi", "theta_l", "theta_r"))
Q_FULL = [x, y, phi, psi, thl, thr]
tau_l, tau_r, tau_d = sp.symbols("tau_l tau_r tau_d")

SEED_VALUES = {g: 9.8, m: 0.03, R: 0.04, Jw: 0.03 * 0.04 ** 2 / 2, Mb: 0.6, W: 0.14, L: 0.072,
               Jpsi: 0.6 * 0.072 ** 2 / 3, Jphi: 0.6 * (0.14 ** 2 + 0.04 ** 2) / 12}


def _energies():
    """T and U in full coordinates, from the positions."""
    heading = sp.Matrix([sp.cos(phi), sp.sin(phi), 0])
    left = sp.Matrix([-sp.sin(phi), sp.cos(phi), 0])
    axle = sp.Matrix([x, y, R])
    wheel_l, wheel_r = axle + W / 2 * left, axle - W / 2 * left
    body = axle + L * (sp.sin(psi) * heading + sp.Matrix([0, 0, sp.cos(psi)]))
    v = [p.diff(t) for p in (wheel_l, wheel_r, body)]
    T = (m / 2 * (v[0].dot(v[0]) + v[1].dot(v[1])) + Mb / 2 * v[2].dot(v[2])
         + Jpsi / 2 * psi.diff(t) ** 2 + Jphi / 2 * phi.diff(t) ** 2
         + Jw / 2 * (thl.diff(t) ** 2 + thr.diff(t) ** 2))
    U = m * g * wheel_l[2] + m * g * wheel_r[2] + Mb * g * body[2]
    return sp.simplify(T), U


@functools.lru_cache(maxsize=None)
def full_coordinate_model():
    """Numerical (M, rhs, A, A'q') functions of (q, q', tau) in full coordinates."""
    T, U = _energies()
    qd = [q.diff(t) for q in Q_FULL]
    qdd = [q.diff(t, 2) for q in Q_FULL]
    # Virtual work of the motors (wheel vs body) and of the disturbance on the body.
    Q = sp.Matrix([0, 0, 0, -tau_l - tau_r + tau_d, tau_l, tau_r])
    eqs = sp.Matrix([(T.diff(v).diff(t) - T.diff(q) + U.diff(q)) for q, v in zip(Q_FULL, qd)])
    Mfull = eqs.jacobian(qdd)
    h = eqs.subs({a: 0 for a in qdd})
    heading_speed = x.diff(t) * sp.cos(phi) + y.diff(t) * sp.sin(phi)
    constraints = sp.Matrix([-x.diff(t) * sp.sin(phi) + y.diff(t) * sp.cos(phi),
                             heading_speed - W / 2 * phi.diff(t) - R * thl.diff(t),
                             heading_speed + W / 2 * phi.diff(t) - R * thr.diff(t)])
    A = constraints.jacobian(qd)
    bias = constraints.diff(t).subs({a: 0 for a in qdd})   # A' q'
    pos = sp.symbols("q0:6")
    vel = sp.symbols("v0:6")
    plain = dict(zip(qd, vel))
    plain_q = dict(zip(Q_FULL, pos))

    def numeric(expr):
        expr = expr.subs(plain).subs(plain_q).subs(SEED_VALUES)
        return sp.lambdify([pos, vel, (tau_l, tau_r, tau_d)], expr, "numpy")

    return numeric(Mfull), numeric(Q - h), numeric(A), numeric(bias)


def oracle_accelerations(theta_state, torques):
    """(theta'', psi'', phi'') by the KKT system, for the state (theta, psi, phi, x, y,
    theta', psi', phi') of the model and torques (tau_l, tau_r, tau_d)."""
    th, ps, ph, px, py, dth, dps, dph = theta_state
    M, rhs, A, bias = full_coordinate_model()
    r, w = SEED_VALUES[R], SEED_VALUES[W]
    half = w / (2 * r)
    q = [px, py, ph, ps, th - half * ph, th + half * ph]
    dq = [r * dth * np.cos(ph), r * dth * np.sin(ph), dph, dps, dth - half * dph, dth + half * dph]
    Mn, An = np.array(M(q, dq, torques), float), np.array(A(q, dq, torques), float)
    kkt = np.block([[Mn, An.T], [An, np.zeros((3, 3))]])
    right = np.concatenate([np.array(rhs(q, dq, torques), float).ravel(),
                            -np.array(bias(q, dq, torques), float).ravel()])
    a = np.linalg.solve(kkt, right)[:6]
    return np.array([(a[4] + a[5]) / 2, a[3], a[2]])


def random_states(n, seed):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        state = np.concatenate([rng.uniform(-3, 3, 1), rng.uniform(-1.4, 1.4, 1), rng.uniform(-3, 3, 3),
                                rng.uniform(-20, 20, 1), rng.uniform(-8, 8, 1), rng.uniform(-10, 10, 1)])
        yield state, tuple(rng.uniform(-0.3, 0.3, 3))


def test_exact_model_matches_lagrange_multipliers_at_random_states():
    """Catches the wheeled pendulum's exact accelerations differing from an independent derivation with
    Lagrange multipliers beyond 1e-12 relative."""
    from plant.wheeled import WheeledPendulum

    plant = WheeledPendulum()
    worst = 0.0
    for state, torques in random_states(60, seed=14):
        expected = oracle_accelerations(state, torques)
        got = plant.derivative(state, *torques)[5:8]
        scale = max(1.0, float(np.max(np.abs(expected))))
        worst = max(worst, float(np.max(np.abs(got - expected))) / scale)
    assert worst <= 1e-12, f"largest relative acceleration difference {worst:.3g}"


def test_seed_model_misses_exactly_the_nonholonomic_terms_numerically():
    """model='seed' differs from the oracle; adding back the two terms closes the gap."""
    from plant.wheeled import SEED, WheeledPendulum

    plant = WheeledPendulum(model="seed")
    p = SEED
    for state, torques in random_states(20, seed=3):
        _, ps, _, _, _, dth, dps, dph = state
        expected = oracle_accelerations(state, torques)
        got = plant.derivative(state, *torques)[5:8]
        # Forcing of the missing terms, moved to the right-hand side, through M^-1.
        c, s = np.cos(ps), np.sin(ps)
        m11 = (2 * p.m + p.M) * p.R ** 2 + 2 * p.J_w
        m12, m22 = p.M * p.R * p.L * c, p.M * p.L ** 2 + p.J_psi
        m33 = 0.5 * p.m * p.W ** 2 + p.M * p.L ** 2 * s * s + p.J_phi + p.W ** 2 / (2 * p.R ** 2) * p.J_w
        extra = np.linalg.solve([[m11, m12], [m12, m22]], [p.M * p.L * p.R * s * dph ** 2, 0.0])
        missing = np.array([extra[0], extra[1], -p.M * p.L * p.R * s * dth * dph / m33])
        if abs(s * dph) > 0.1:
            assert np.max(np.abs(got - expected)) > 1e-3
        np.testing.assert_allclose(got + missing, expected, rtol=1e-11, atol=1e-11)


def test_nonholonomic_terms_symbolically():
    """Lagrange-d'Alembert minus the substituted Lagrangian (seed (13)-(16)) is exactly
    (-M L R sin(psi) phi'^2, 0, M L R sin(psi) theta' phi') in the (theta, psi, phi) rows."""
    T, U = _energies()
    th, ph_ = sp.Function("theta")(t), phi
    half = W / (2 * R)
    # Constrained velocities q' = S(q) nu', nu = (theta, psi, phi).
    on_constraint = {thl: th - half * ph_, thr: th + half * ph_}
    velocities = {x.diff(t): R * th.diff(t) * sp.cos(ph_), y.diff(t): R * th.diff(t) * sp.sin(ph_)}
    accelerations = {a: sp.diff(b, t) for a, b in ((x.diff(t, 2), velocities[x.diff(t)]),
                                                   (y.diff(t, 2), velocities[y.diff(t)]))}

    def constrained(expr):
        expr = expr.subs(accelerations).subs(velocities)
        return sp.simplify(expr.subs(on_constraint).doit())

    # Lagrange-d'Alembert: S^T (d/dt dT/dq' - dT/dq + dU/dq) in full coordinates.
    rows = {q: T.diff(q.diff(t)).diff(t) - T.diff(q) + U.diff(q) for q in Q_FULL}
    S = {th: {x: R * sp.cos(ph_), y: R * sp.sin(ph_), thl: 1, thr: 1},
         psi: {psi: 1}, ph_: {ph_: 1, thl: -half, thr: half}}
    dalembert = {nu: constrained(sum(coef * rows[q] for q, coef in col.items())) for nu, col in S.items()}
    # Seed: constraints substituted into the Lagrangian, then Euler-Lagrange in (theta, psi, phi).
    Lsub = (T - U).subs(velocities).subs(on_constraint).doit()
    seed = {nu: sp.simplify(Lsub.diff(nu.diff(t)).diff(t) - Lsub.diff(nu)) for nu in (th, psi, ph_)}
    difference = [sp.simplify(dalembert[nu] - seed[nu]) for nu in (th, psi, ph_)]
    expected = [-Mb * L * R * sp.sin(psi) * ph_.diff(t) ** 2, 0,
                Mb * L * R * sp.sin(psi) * th.diff(t) * ph_.diff(t)]
    for got, want in zip(difference, expected):
        assert sp.simplify(got - want) == 0, (got, want)
