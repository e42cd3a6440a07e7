"""The control law (7.21-7.22, 6.65-6.66) against the thesis' definitions and the closed-loop physics.

Written from the thesis' text (chapter 6.3, 7.2.6), not from our code: the sliding variable
s = ë + kv ė + kp e (7.22) with e = r_d - r (6.5); the adaptive gain (6.66) on a hand-made
sequence of s; and what the sliding term is for: with a model error and a constant
disturbance, the integral of k sat(s/phi) (7.21) removes the steady error that the PD law
keeps (e = -d / (m* kp)).  The law is the C kernel (kernels/src/law.c); the exact model's
terms come from the 5R kernel ("fast") or the general algorithm ("general").
"""
import ctypes
import dataclasses
import math

import numpy as np
import pytest

import kernels
from controller import law
from controller.position import PositionController
from controller.strategies import get_strategy
from plant import fivebar, get_preset
from tests.support.strategies import strategy_read_from_a_file

BENCH = get_preset("bench")
KERNELS = ("fast", "general")
#: The reference point: the start of the circle (7.23), well inside the workspace.
X_REF, Y_REF = 0.0, 0.108


def _reference_angles():
    ang = fivebar.inverse_kinematics(BENCH, X_REF, Y_REF)
    return ang[0], ang[2]


def _s_after_one_sample(kernel, name, q, dq, ddq):
    """s of a fresh controller holding (X_REF, Y_REF) at rest, for the measured q, dq, ddq
    (name: a strategy's name or the strategy itself)."""
    ctrl = PositionController(BENCH, get_strategy(name) if isinstance(name, str) else name, kernel=kernel)
    ctrl.step(0.0, *q, *dq, *ddq, X_REF, Y_REF, 0.0, 0.0, 0.0, 0.0)
    return np.array(ctrl.s), np.array(ctrl.e), ctrl


@pytest.mark.parametrize("kernel", KERNELS)
def test_sliding_variable_is_7_22_in_joint_space(kernel):
    """Joint space: r = q, and the reference (held point) does not depend on the measurement,
    so (7.22) with e = q_d - q (6.5) gives ∂s/∂q̈ = -1, ∂s/∂q̇ = -kv, ∂s/∂q = -kp exactly
    (s is linear in the measurement).  A flipped sign of ë gives ∂s/∂q̈ = +1."""
    qr = _reference_angles()
    q = (qr[0] + 0.01, qr[1] - 0.02)
    dq, ddq = (0.3, -0.2), (5.0, -7.0)
    s0, e0, ctrl = _s_after_one_sample(kernel, "PDMDq", q, dq, ddq)
    kp, kv = ctrl.strategy.lam ** 2, 2.0 * ctrl.strategy.lam
    assert np.allclose(e0, np.subtract(qr, q), rtol=0, atol=1e-12)              # (6.5)
    assert np.allclose(s0, kp * e0 - kv * np.array(dq) - np.array(ddq), rtol=1e-12)   # (7.22), r_d at rest
    d = 0.5
    s1, _, _ = _s_after_one_sample(kernel, "PDMDq", q, dq, (ddq[0] + d, ddq[1] - d))
    assert np.allclose(s1 - s0, (-d, d), rtol=1e-9)
    s2, _, _ = _s_after_one_sample(kernel, "PDMDq", q, (dq[0] + d, dq[1]), ddq)
    assert np.allclose(s2 - s0, (-kv * d, 0.0), rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("source", ["preset", "file"])
@pytest.mark.parametrize("kernel", KERNELS)
def test_sliding_variable_is_7_22_in_task_space(kernel, source):
    """Task space: r = x = FK(q) and ẍ = J q̈ + β, so changing q̈ by δ changes s by -J δ.
    J here is a central difference of the plant's forward kinematics (7.1-7.16), not the
    controller's analytic Jacobian.  The same for the strategy read from a file."""
    strategy = get_strategy("PDMDx") if source == "preset" else strategy_read_from_a_file("PDMDx")
    qr = _reference_angles()
    q = (qr[0] + 0.005, qr[1] + 0.004)
    dq, ddq = (0.2, 0.1), (1.0, 2.0)
    s0, _, _ = _s_after_one_sample(kernel, strategy, q, dq, ddq)
    delta = np.array([0.7, -0.3])
    s1, _, _ = _s_after_one_sample(kernel, strategy, q, dq, tuple(np.add(ddq, delta)))
    assert np.allclose(s1 - s0, -_jacobian_by_differences(q) @ delta, rtol=1e-6, atol=1e-9)


def _jacobian_by_differences(q, h=1e-6):
    """∂(x, y)/∂(q1, q2) by central differences of the plant's forward kinematics (7.1-7.16)."""
    J = np.empty((2, 2))
    for j in (0, 1):
        plus, minus = list(q), list(q)
        plus[j] += h
        minus[j] -= h
        J[:, j] = (fivebar.direct_kinematics(BENCH, *plus) - fivebar.direct_kinematics(BENCH, *minus))[:2] / (2 * h)
    return J


_IO = kernels.function("pc_law_io", ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                       ctypes.POINTER(kernels.Refusal))


def test_compiled_loop_entry_reads_its_inputs_in_the_documented_order():
    """The compiled scene loop calls the law as ``pc_law_io(context, x, t, h, refusal)`` with
    x = [q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d | tau1, tau2, ...].
    PDx has k = 0, Ĥ = m*·1, ĥ = 0, so τ = Jᵀ m* (ẍ_d + kv ė + kp e) (7.21): a change δ of the
    reference acceleration (ẍ_d, ÿ_d) changes τ by m* Jᵀ δ, whatever the output slots hold."""
    qr = _reference_angles()
    q = (qr[0] + 0.005, qr[1] + 0.004)

    def torques(ddx_d, ddy_d):
        ctrl = PositionController(BENCH, get_strategy("PDx"), kernel="fast")
        x = np.full(18, 7.0)                            # output slots: stale values from a last sample
        x[:12] = (*q, 0.2, 0.1, 1.0, 2.0, X_REF, Y_REF, 0.0, 0.0, ddx_d, ddy_d)
        context = law.loop_context(ctrl._binding(), np.zeros((0, 4)))
        assert _IO(ctypes.addressof(context), x.ctypes.data, 0.0, 1e-3, kernels.Refusal()) == law.OK
        return x[12:14].copy(), ctrl.strategy.m_star

    tau0, m_star = torques(0.0, 0.0)
    delta = np.array([0.3, -0.4])
    tau1, _ = torques(*delta)
    assert np.allclose(tau1 - tau0, m_star * _jacobian_by_differences(q).T @ delta, rtol=1e-6, atol=1e-12)


def _adaptive_run(kernel, s_sequence, k0, gamma, phi):
    """Feed the PD law (joint space, e = ė = 0, r_d at rest) with q̈ = -s so that s (7.22)
    takes the given values; return the gains k and the integrals after each sample."""
    st = get_strategy("PDMDq").with_(k=(k0, k0), gamma=(gamma, gamma), phi=phi)
    ctrl = PositionController(BENCH, st, kernel=kernel)
    q = _reference_angles()
    gains, integrals = [], []
    for n, s in enumerate(s_sequence):
        tau = ctrl.step(n * 1e-3, *q, 0.0, 0.0, -s, -s, X_REF, Y_REF, 0.0, 0.0, 0.0, 0.0)
        assert ctrl.e == [0.0, 0.0] and ctrl.s == [s, s]     # exact: the |s| = phi cases are on the boundary
        gains.append(ctrl.k[0])
        integrals.append(tau[0] / st.m_star)          # u' = m* (0 + 0 + I) when e = ė = 0, r̈_d = 0
    return gains, integrals


@pytest.mark.parametrize("kernel", KERNELS)
def test_adaptive_gain_follows_6_66_on_a_known_sequence(kernel):
    """(6.66) by hand, phi = 20, gamma = 5, k0 = 200: outside the layer k grows by gamma
    while s keeps its sign; inside it k holds while s keeps its sign and drops by gamma at
    each crossing; the first sample (s[-1] = 0) keeps k."""
    s = [30.0, 30.0, 10.0, -10.0, -5.0, 5.0, 25.0, -25.0, -25.0, -19.0, -20.0, 20.0, 20.0, 0.0, 5.0]
    # |s| = phi: ">=" grows; sinal(0) = 0: s = 0 (and the sample after it) keeps k.
    expected = [200, 205, 205, 200, 200, 195, 200, 195, 200, 200, 205, 200, 205, 205, 205]
    gains, integrals = _adaptive_run(kernel, s, 200.0, 5.0, 20.0)
    assert gains == expected
    # The integral of (7.21) with the rectangle rule, each sample with its updated gain.
    sat = [max(-1.0, min(1.0, v / 20.0)) for v in s]
    assert integrals == pytest.approx(np.cumsum(1e-3 * np.array(expected) * sat), rel=1e-12)


@pytest.mark.parametrize("kernel", KERNELS)
def test_adaptive_gain_stays_positive_through_zero(kernel):
    """|k + gamma sign(s[k]) sign(s[k-1])| (6.66): a crossing with k < gamma reflects k at zero
    (1 - 5 → 4, 4 - 5 → 1); the integral of (7.21) takes every gain, k = 1 included."""
    s = [1.0, -1.0, 1.0, -1.0]
    gains, integrals = _adaptive_run(kernel, s, 1.0, 5.0, 20.0)
    assert gains == [1.0, 4.0, 1.0, 4.0]
    assert integrals == pytest.approx(np.cumsum(1e-3 * np.array(gains) * np.array(s) / 20.0), rel=1e-12)


def _double_integrator_error(kernel, name, duration=1.5, mass_ratio=1.3, disturbance=(-2e-3, 1.5e-3)):
    """Joint-space law on two decoupled inertias m = mass_ratio m* with a constant disturbance
    torque d (N m); torques held over T = 1 ms, exact ZOH integration; the measured q̈ is the
    acceleration of the last interval.  Returns the error of each joint at the end."""
    st = get_strategy(name)
    ctrl = PositionController(BENCH, st, kernel=kernel)
    q_ref = np.array(_reference_angles())
    q, dq, ddq = q_ref.copy(), np.zeros(2), np.zeros(2)
    m, d, T = mass_ratio * st.m_star, np.array(disturbance), 1e-3
    for n in range(int(round(duration / T))):
        tau = np.array(ctrl.step(n * T, *q, *dq, *ddq, X_REF, Y_REF, 0.0, 0.0, 0.0, 0.0)[:2])
        ddq = (tau + d) / m
        q = q + dq * T + 0.5 * ddq * T * T
        dq = dq + ddq * T
    return q_ref - q


@pytest.mark.parametrize("kernel", KERNELS)
def test_sliding_term_removes_the_steady_error_of_a_constant_disturbance(kernel):
    """PD (Table 6): at rest m* kp e + d = 0, so e = -d / (m* kp) (7.21 with k = 0) and the
    simulation reproduces it.  PDMD: inside the boundary layer the integral of k s / phi is
    an integral action, so the error goes to zero
    (9.6e-7 of it after 1.5 s, an exponential decay at 9.3 /s); the bound 1e-5 fails a law whose
    integral action decays 17 % slower.
    A flipped ë in s turns the integral into a positive feedback and the error grows."""
    st = get_strategy("PDq")
    e_pd = _double_integrator_error(kernel, "PDq")
    d = np.array((-2e-3, 1.5e-3))
    assert e_pd == pytest.approx(-d / (st.m_star * st.lam ** 2), rel=1e-6)
    e_md = _double_integrator_error(kernel, "PDMDq")
    assert np.all(np.abs(e_md) < 1e-5 * np.abs(e_pd))


@pytest.mark.parametrize("kernel", KERNELS)
def test_step_with_errors_returns_both_errors_6_5(kernel):
    """e = q_d - q (6.5) of each joint, from the compiled and from the Python path."""
    qr = _reference_angles()
    q = (qr[0] + 0.01, qr[1] - 0.02)
    ctrl = PositionController(BENCH, get_strategy("PDq"), kernel=kernel)
    out = ctrl.step_with_errors(0.0, *q, 0.0, 0.0, 0.0, 0.0, X_REF, Y_REF, 0.0, 0.0, 0.0, 0.0)
    assert out[4:] == pytest.approx((-0.01, 0.02), abs=1e-12)


@pytest.mark.parametrize("T", [0.0, -1e-3, float("nan")])
def test_sample_time_must_be_positive(T):
    """Catches a controller built with T = 0, T < 0 or NaN (its derivatives would divide by it)."""
    with pytest.raises(ValueError, match=r"T = .* s must be > 0"):
        PositionController(BENCH, get_strategy("PDq"), T=T)


def test_pd_strategy_needs_a_positive_m_star():
    """u' = m* (...) (7.21, PD): m* = 0 would command no torque at all."""
    with pytest.raises(ValueError, match=r"m_star = 0.0 must be > 0 for the PD strategy PDq"):
        PositionController(BENCH, get_strategy("PDq").with_(m_star=0.0))


@pytest.mark.parametrize("kernel", KERNELS)
def test_exact_model_law_refuses_a_pose_without_assembly_naming_it(kernel):
    """q1 = 0, q2 = pi puts the elbows at (±(l0 + l11), 0), 0.34 m apart, farther than the two
    distal links (2 × 0.16 m) reach (002 eq. 7-11): there is no end effector, so no task state
    and no model terms.  The sample is refused with the measured angles and the time."""
    ctrl = PositionController(BENCH, get_strategy("TCx"), model="exact", kernel=kernel)
    elbow_gap = 2 * BENCH.l0 + BENCH.chain1.l1 + BENCH.chain2.l1
    assert elbow_gap > BENCH.chain1.l2 + BENCH.chain2.l2
    with pytest.raises(ValueError, match=r"measured \(q1, q2\) = \(0\.0, 3\.14159.*\) rad at t = 0\.25 s"):
        ctrl.step(0.25, 0.0, math.pi, 0.0, 0.0, 0.0, 0.0, X_REF, Y_REF, 0.0, 0.0, 0.0, 0.0)


def _potential_energy(params, q1, q2):
    """V = -Σ m g·r over the links' centres of mass (lg from the proximal joint) and the end
    effector, from the plant's kinematics (elbows, tip) only."""
    g = np.array(params.gravity[:2])
    a = fivebar.elbows(params, q1, q2)
    tip = fivebar.direct_kinematics(params, q1, q2)[:2]
    v = -params.m0 * g @ tip
    for chain, base, elbow in zip((params.chain1, params.chain2), fivebar.bases(params), a):
        v -= chain.m1 * g @ (base + chain.lg1 / chain.l1 * (elbow - base))
        v -= chain.m2 * g @ (elbow + chain.lg2 / chain.l2 * (tip - elbow))
    return v


@pytest.mark.parametrize("name", ["TCq", "TCx"])
@pytest.mark.parametrize("kernel", KERNELS)
def test_exact_model_law_holds_the_robot_against_gravity(kernel, name):
    """The bench upright (g = -9.81 m/s² along y, as the vertical scenes): at rest on its
    reference (e = ė = ë = 0, r̈_d = 0), TC commands u' = ĥ = the gravity term (7.21), in
    either space, which by virtual work is τ = ∂V/∂q, V the potential energy of links and end
    effector (central differences of the kinematics, not the model's g_M)."""
    params = dataclasses.replace(BENCH, gravity=(0.0, -9.81, 0.0))
    q = _reference_angles()
    ctrl = PositionController(params, get_strategy(name), model="exact", kernel=kernel)
    tau = ctrl.step(0.0, *q, 0.0, 0.0, 0.0, 0.0, X_REF, Y_REF, 0.0, 0.0, 0.0, 0.0)[:2]
    h = 1e-6
    grad = [(_potential_energy(params, *np.add(q, d)) - _potential_energy(params, *np.subtract(q, d))) / (2 * h)
            for d in ((h, 0.0), (0.0, h))]
    assert abs(grad[0]) > 0.05 and abs(grad[1]) > 0.05            # gravity loads both joints
    assert np.allclose(tau, grad, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("y", [1e-6, 0.0, -0.0, -1e-6])
def test_a_joint_space_reference_on_the_base_line_is_the_plants_inverse_kinematics_of_it(y):
    """At the reference point (0, y) on (or beside) the bases' line, at rest at the angles
    plant.fivebar.inverse_kinematics gives for it, a PD law in joint space has no error and no
    torque: its joint reference is that closed form's, in its branch too (chain 1's angle takes
    the branch of atan2's y sign bit: y = -0.0 is a full turn from +0.0).  Catches the
    reference changed before its inverse kinematics when no delay is predicted (0 * rate added:
    -0.0 becomes +0.0, a 2 pi error)."""
    params = get_preset("bench")
    q1, _, q2, _ = fivebar.inverse_kinematics(params, 0.0, y)
    ctrl = PositionController(params, get_strategy("PDq"))
    tau1, tau2, _, _, e1, e2 = ctrl.step_with_errors(0.0, q1, q2, 0.0, 0.0, 0.0, 0.0, 0.0, y, 0.0, 0.0, 0.0, 0.0)
    assert (e1, e2) == (0.0, 0.0) and (tau1, tau2) == (0.0, 0.0)
