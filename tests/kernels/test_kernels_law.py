"""The position law's C kernel (kernels/src/law.c) and the 5R kinematics (kinematics5r.c)
against oracles that share no code with them.

* the kinematics against the general algorithm (plant/serial.py + plant/parallel.py): the
  serial chains close at the kernel's pose (residual 5.18), its rates and accelerations are
  C dx# and C ddx# + c (5.56, 5.69);
* one sample of the law against (7.21-7.22), seed 001's law and (6.65) written here from the
  thesis, with the model terms and the torque map Z (5.72) of the general algorithm: every
  strategy, both spaces, exact and tabulated models, two samples (the integral carries over);
* the adaptive gain (6.66) integrated over a constant error against its closed form;
* the tabulated model's interpolation against scipy's RegularGridInterpolator;
* the compiled loop's I/O with the exact model's terms from a terms function.
"""
import ctypes
import math

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

import kernels
from controller import law
from controller.kinematics import Kinematics
from controller.model import ModelRangeError, TabulatedModel
from controller.position import PositionController
from controller.strategies import ALL_STRATEGY_NAMES, get_strategy
from plant import fast5r, fivebar, get_preset
from plant.parallel import inverse_dynamics_terms, mechanism_state
from tests.support.poses import random_poses

BENCH = get_preset("bench")
MECH = fivebar.build_mechanism(BENCH)
TH11, TH21 = fivebar.TH11, fivebar.TH21
H = 1e-3
NEAR = fivebar.NEAR_SINGULAR_MARGIN


def general_terms(x, y, dx, dy):
    """C, c, M_M, v_M + g_M and Z at the end effector's (x, y, dx, dy), by the general algorithm
    (thesis coordinates of the working mode from plant.fivebar, checked by the closure residual)."""
    q7 = fivebar.thesis_coordinates(BENCH, x, y)
    state = mechanism_state(MECH, q7, np.zeros(7))
    assert np.abs(state.residual).max() < 1e-12
    dq7 = state.C @ (dx, dy)
    t = inverse_dynamics_terms(MECH, q7, dq7)
    return state.C, t.c, t.M, t.v + t.g, t.Z


def joint_motion(x, y, dx, dy, ddx, ddy):
    """World (q1, q2, dq1, dq2, ddq1, ddq2) of the end effector's motion: dq = C dx#,
    ddq = C ddx# + c (5.56, 5.69), chain 2's angle mirrored (7.4)."""
    C, c, _, _, _ = general_terms(x, y, dx, dy)
    q7 = fivebar.thesis_coordinates(BENCH, x, y)
    dq7, ddq7 = C @ (dx, dy), C @ (ddx, ddy) + c
    return (q7[TH11], math.pi - q7[TH21], dq7[TH11], -dq7[TH21], ddq7[TH11], -ddq7[TH21])


# --- kinematics ----------------------------------------------------------------------------------
def test_kinematics_close_the_general_algorithms_chains():
    """The kernel's inverse and direct kinematics give a pose where both DH chains of the general
    algorithm meet (residual 5.18 = 0) with the actuated angles asked for; its J, beta and thesis
    rates are the general algorithm's C and c (5.56, 5.69)."""
    kin = Kinematics(BENCH)
    rng = np.random.default_rng(5)
    for x, y in random_poses(BENCH, rng, 25, band=0.15, ys=(0.05, 0.28)):
        p11, p12, p21, p22 = kin.inverse(x, y)
        q7 = np.array([x, y, 0.0, p11, p12 - p11, math.pi - p21, p21 - p22])
        state = mechanism_state(MECH, q7, np.zeros(7))
        assert np.abs(state.residual).max() < 1e-13
        assert np.allclose(kin.forward(p11, p21), (x, y), rtol=0, atol=1e-14)
        dxy, ddxy = rng.normal(0.0, 0.5, 2), rng.normal(0.0, 5.0, 2)
        q, dq = kin.thesis_state(x, y, *dxy)
        assert np.allclose(q, q7, atol=1e-14) and np.allclose(dq, state.C @ dxy, rtol=1e-12, atol=1e-12)
        c = inverse_dynamics_terms(MECH, q7, dq).c
        ddq7 = state.C @ ddxy + c
        task = kin.task_state(p11, p21, dq[TH11], -dq[TH21], ddq7[TH11], -ddq7[TH21])
        assert np.allclose(task[:2], (x, y), atol=1e-14)
        assert np.allclose(task[2:4], dxy, rtol=1e-11, atol=1e-12)
        assert np.allclose(task[4:6], ddxy, rtol=1e-10, atol=1e-10)
        joint = kin.joint_reference(x, y, *dxy, *ddxy)
        assert np.allclose(joint, (p11, p21, dq[TH11], -dq[TH21], ddq7[TH11], -ddq7[TH21]), rtol=1e-10, atol=1e-10)


def test_kinematics_refuse_what_the_mechanism_cannot_take():
    """Catches C kinematics returning NaN or a wrong pose where the chain cannot reach or assemble,
    and task_state refusing a pose without assembly with another text (or error) than forward's."""
    kin = Kinematics(BENCH)
    with pytest.raises(fivebar.KinematicsError, match=r"out of reach of a chain \(distance 0\.45 m\)"):
        kin.inverse(0.5, 0.0)                                   # 0.45 m from chain 1's base at (l0, 0)
    with pytest.raises(fivebar.KinematicsError, match=r"no assembly for q1=0, q2=3\.14159 rad \(elbow distance 0\.34") as forward:
        kin.forward(0.0, math.pi)
    with pytest.raises(fivebar.KinematicsError) as task:      # the same pose, the same text
        kin.task_state(0.0, math.pi, 0.1, -0.2, 0.3, 0.4)
    assert str(task.value) == str(forward.value)


def test_chain_ik_takes_the_branch_of_the_difference_of_two_atan2():
    """Catches the one-atan2 inverse kinematics (pc_5r_chain_ik turns (px, py) back by the elbow
    triangle's angle and puts the result on the branch of atan2(py, px) - atan2(b, a)) slipping by
    2 pi or taking the wrong elbow: phi1 within 1e-14 rad of the two-atan2 formula written here,
    and the chain closing on the point, at random points of the annulus of reach, both elbows,
    and on the axes with +0 and -0 (where atan2 takes the sign bit)."""
    d, p = ctypes.c_double, ctypes.POINTER(ctypes.c_double)
    chain_ik = kernels.function("pc_5r_chain_ik", ctypes.c_int, d, d, d, d, d, p, p, p)
    rng = np.random.default_rng(27)
    points = [(r * math.cos(a), r * math.sin(a)) for r, a in zip(rng.uniform(0.03, 0.27, 4000),
                                                                 rng.uniform(-math.pi, math.pi, 4000))]
    points += [(sx * r, sy * 0.0) for r in (0.05, 0.15, 0.25) for sx in (1.0, -1.0) for sy in (1.0, -1.0)]
    points += [(sx * 0.0, sy * r) for r in (0.05, 0.15, 0.25) for sx in (1.0, -1.0) for sy in (1.0, -1.0)]
    l1, l2 = 0.15, 0.13
    for px, py in points:
        for elbow in (1.0, -1.0):
            phi1, phi2, distance = d(), d(), d()
            assert chain_ik(l1, l2, px, py, elbow, phi1, phi2, distance) == 0
            beta = elbow * math.acos((px * px + py * py - l1 * l1 - l2 * l2) / (2.0 * l1 * l2))
            expected = math.atan2(py, px) - math.atan2(l2 * math.sin(beta), l1 + l2 * math.cos(beta))
            assert abs(phi1.value - expected) < 1e-14, (px, py, elbow, phi1.value, expected)
            assert abs(phi2.value - (expected + beta)) < 1e-14
            tip = (l1 * math.cos(phi1.value) + l2 * math.cos(phi2.value),
                   l1 * math.sin(phi1.value) + l2 * math.sin(phi2.value))
            assert np.allclose(tip, (px, py), rtol=0, atol=1e-15)


def test_clear_passes_only_references_the_angles_would_pass():
    """Catches pc_5r_clear (the task-space law's check of a reference without acos and atan2)
    letting through a reference that the angles and pc_5r_margin would refuse, or a wrong
    direction formula: at random points in and out of reach it is 0 out of reach, 0 with the band
    at the exact margin or 1e-10 below it (its slack), 1 with the band 5e-9 below it when both
    elbows are clear of 1e-3 (its margin within 4e-9 of the exact one), and 0 whenever the margin
    is below the band."""
    from plant import kinematics5r as k5r
    g = k5r.geometry(BENCH)
    clear = kernels.function("pc_5r_clear", ctypes.c_int, ctypes.POINTER(k5r.Geometry), ctypes.c_double,
                             ctypes.c_double, ctypes.c_double)
    rng = np.random.default_rng(38)
    reach = g.l0 + max(g.l11 + g.l12, g.l21 + g.l22)
    tested = 0
    for x, y in rng.uniform(-reach, reach, (4000, 2)):
        angles, distance = (ctypes.c_double * 4)(), ctypes.c_double()
        if k5r.inverse(g, x, y, angles, distance) != k5r.OK:
            assert clear(g, x, y, 0.0) == 0 and clear(g, x, y, -1.0) == 0
            continue
        m = k5r.margin(angles)
        serial = min(abs(math.sin(angles[1] - angles[0])), abs(math.sin(angles[3] - angles[2])))
        assert clear(g, x, y, m) == 0 and clear(g, x, y, m - 1e-10) == 0 and clear(g, x, y, m + 1e-3) == 0
        if m < NEAR:
            assert clear(g, x, y, NEAR) == 0
        elif m > NEAR + 1e-8 and serial > 1.001e-3:
            assert clear(g, x, y, NEAR) == 1
        if serial > 1.001e-3:
            assert clear(g, x, y, m - 5e-9) == 1, (x, y, m)
            tested += 1
    assert tested > 1000


# --- the law, one sample at a time ----------------------------------------------------------
#: A measured motion of the end effector and the reference a few mm away, moving differently.
MEASURED = (0.010, 0.150, 0.10, -0.05, 0.8, -0.6)
REFERENCES = [(0.012, 0.1485, 0.12, -0.02, 0.3, 0.2), (0.0125, 0.149, 0.05, 0.04, -1.0, 0.5)]


def sat(v):
    return max(-1.0, min(1.0, v))


def oracle_sample(st, model, reference, memory):
    """(tau1, tau2, e1, e2) of one sample from the thesis' equations, and the law's memory
    (integral I, gains k, previous s) advanced in ``memory``."""
    x, y, dx, dy, ddx, ddy = MEASURED
    C, c, M, hvec, Z = general_terms(x, y, dx, dy)
    if model == "tabulated":
        M00, M01, M11, h0, h1 = memory["table"].terms(x, y, dx, dy)
        M, hvec = np.array([[M00, M01], [M01, M11]]), np.array([h0, h1])
    if st.space == "x":
        r, rd = np.array(MEASURED).reshape(3, 2), np.array(reference).reshape(3, 2)
    else:
        r = np.array(joint_motion(*MEASURED)).reshape(3, 2)
        rd = np.array(joint_motion(*reference)).reshape(3, 2)
    e, de, dde = rd[0] - r[0], rd[1] - r[1], rd[2] - r[2]
    lam = st.lam
    if st.law == "seed001":                                   # seed 001, section 1.2
        s = de + lam * e
        a = rd[2] + lam * de + memory["k"] * np.array([sat(v / st.phi) for v in s])
    else:
        s = dde + 2 * lam * de + lam ** 2 * e                  # (7.22), kv = 2 lam, kp = lam^2
        memory["I"] = memory["I"] + H * memory["k"] * np.array([sat(v / st.phi) for v in s])   # (6.65)
        a = rd[2] + 2 * lam * de + lam ** 2 * e + memory["I"]   # (7.21)
    if st.space == "q":      # the task acceleration of the joint acceleration a: C_act ddx# + c_act = a
        A = np.array([C[TH11], -C[TH21]])
        a = np.linalg.solve(A, a - np.array([c[TH11], -c[TH21]]))
    f = st.m_star * a if not st.model_based else M @ a + hvec
    if st.space == "q" and not st.model_based:
        tau = st.m_star * (rd[2] + 2 * lam * de + lam ** 2 * e + memory["I"])
    else:
        tau = np.array(fivebar.world_torques(np.linalg.solve(Z.T, f)))   # u' = Z^T u* (5.72)
    return tau, e


@pytest.mark.parametrize("model", ["exact", "tabulated"])
@pytest.mark.parametrize("name", ALL_STRATEGY_NAMES)
def test_two_samples_follow_the_thesis_equations(name, model, tmp_path, monkeypatch):
    """Catches a law kernel whose torques of two samples differ from (7.21)-(7.22) written in the test."""
    st = get_strategy(name)
    if not st.model_based and model == "tabulated":
        pytest.skip("PD strategies use no model")   # their "exact" case runs them
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    ctrl = PositionController(BENCH, st, model=model, grid_step=0.01, extent=(-0.05, 0.05, 0.10, 0.20))
    memory = {"I": np.zeros(2), "k": np.array(st.k), "table": ctrl.model}
    q = joint_motion(*MEASURED)
    for n, reference in enumerate(REFERENCES):
        got = ctrl.step_with_errors(n * H, *q, *reference, H)
        tau, e = oracle_sample(st, model, reference, memory)
        assert np.allclose(got[:2], tau, rtol=1e-8, atol=1e-12), (n, got, tau)
        assert got[2:4] == (got[0] / ctrl.kt[0], got[1] / ctrl.kt[1])
        assert np.allclose(got[4:], e, rtol=1e-9, atol=1e-13)
    if st.law == "unified" and any(st.k):
        assert np.allclose(ctrl.integral, memory["I"], rtol=1e-9, atol=1e-12)
        assert np.abs(memory["I"]).max() > 0.1                   # the integral enters the torques


def test_adaptive_gain_integrates_to_its_closed_form_for_a_constant_error():
    """A constant error e at rest: s = kp e (7.22), |s| > phi and of one sign, so (6.66) adds gamma
    to k from the second sample on (the first has no previous s: sign 0), and the integral (6.65)
    after N samples is h sign(s) (N k0 + gamma N (N - 1) / 2)."""
    k0, gamma, N = 50.0, 4.0, 40
    st = get_strategy("PDMDq").with_(k=(k0, k0), gamma=(gamma, gamma), phi=1.0)
    ctrl = PositionController(BENCH, st)
    x, y = 0.0, 0.15
    q = fivebar.inverse_kinematics(BENCH, x, y)
    measured = (q[0] - 0.01, q[2] + 0.02)                       # e = (+0.01, -0.02) rad
    for n in range(N):
        ctrl.step(n * H, *measured, 0, 0, 0, 0, x, y, 0, 0, 0, 0)
    s = np.array(ctrl.s)
    assert np.allclose(s, st.lam ** 2 * np.array([0.01, -0.02]), rtol=1e-9) and np.all(np.abs(s) > st.phi)
    closed = H * np.sign(s) * (N * k0 + gamma * N * (N - 1) / 2)
    assert np.allclose(ctrl.integral, closed, rtol=1e-12)
    assert np.allclose(ctrl.k, k0 + gamma * (N - 1), rtol=1e-12)


# --- the tabulated model ----------------------------------------------------------------------
def test_interpolation_is_scipys_bilinear_on_random_points(tmp_path, monkeypatch):
    """The kernel's interpolation (pc_law_interpolate) is linear interpolation on the regular grid:
    scipy's RegularGridInterpolator on the same values, at random points of complete cells;
    points in an incomplete cell or off the grid are refused."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    model = TabulatedModel(BENCH, step=0.01, extent=(-0.10, 0.10, 0.02, 0.28))
    assert (~model.cell_ok).any() and model.cell_ok.any()
    oracle = RegularGridInterpolator((model.ys, model.xs), model.table, method="linear")
    rng = np.random.default_rng(1)
    cells = np.argwhere(model.cell_ok)
    for iy, ix in cells[rng.integers(0, len(cells), 300)]:
        x, y = model.xs[ix] + rng.random() * model.step, model.ys[iy] + rng.random() * model.step
        assert np.allclose(model.interpolate(x, y), oracle((y, x)), rtol=1e-12, atol=1e-15)
    iy, ix = np.argwhere(~model.cell_ok)[0]
    with pytest.raises(ModelRangeError, match="left out of the table"):
        model.interpolate(model.xs[ix] + 0.5 * model.step, model.ys[iy] + 0.5 * model.step)
    for x, y in ((-0.1001, 0.1), (0.1001, 0.1), (0.0, 0.0199), (0.0, 0.2801)):
        with pytest.raises(ModelRangeError, match="outside the tabulated region"):
            model.interpolate(x, y)



def test_the_far_edges_and_corners_belong_to_the_table(tmp_path, monkeypatch):
    """A grid of binary-exact numbers (step 2^-7 m, corners at +-2^-6 and 0.140625 / 0.171875
    m) puts the far edges at exactly nx and ny cells: the grid points on every edge and corner
    interpolate to their own table row (scipy's linear interpolation there), the near edges
    as the far ones; a step of 1e-9 m beyond either far edge, or before a near one, is refused
    naming the region.  Catches the range check written without the far edge (fx < nx for
    fx < nx + 1, a point on the last grid line refused) or with the near one moved."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    step = 2.0 ** -7
    model = TabulatedModel(BENCH, step=step, extent=(-2.0 ** -6, 2.0 ** -6, 0.140625, 0.171875))
    assert model.cell_ok.all() and (len(model.xs), len(model.ys)) == (5, 5)
    assert (model.xs[-1] - model.xs[0]) / step == 4.0 and (model.ys[-1] - model.ys[0]) / step == 4.0
    oracle = RegularGridInterpolator((model.ys, model.xs), model.table, method="linear")
    for iy in range(5):
        for ix in (0, 4) if iy not in (0, 4) else range(5):
            x, y = float(model.xs[ix]), float(model.ys[iy])
            np.testing.assert_allclose(model.interpolate(x, y), model.table[iy, ix], rtol=1e-13, atol=1e-15)
            np.testing.assert_allclose(model.interpolate(x, y), oracle((y, x)), rtol=1e-13, atol=1e-15)
    x0, x1, y0, y1 = model.xs[0], model.xs[-1], model.ys[0], model.ys[-1]
    for x, y in ((x1 + 1e-9, 0.15), (x0 - 1e-9, 0.15), (0.0, y1 + 1e-9), (0.0, y0 - 1e-9)):
        with pytest.raises(ModelRangeError, match="outside the tabulated region"):
            model.interpolate(x, y)

# --- the compiled loop's I/O -----------------------------------------------------------------
_TERMS_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.POINTER(ctypes.c_double),
                             ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double))


def test_io_with_a_terms_function_runs_the_exact_model_in_c():
    """pc_law_io (x = 12 inputs then 6 outputs) with the context's terms function computes the
    exact model's sample the Python entry computes; a refused sample leaves x's outputs and the
    state alone and names the input."""
    st = get_strategy("TCMDx")
    ctrl, twin = PositionController(BENCH, st, model="exact"), PositionController(BENCH, st, model="exact")
    p = ctrl.model._p

    def terms_of(_model, q, dq, out):
        inverse_terms_into(p, q, dq, out)

    callback = _TERMS_FN(terms_of)
    context = law.Context.from_buffer_copy(ctrl._binding().context)
    context.terms_of = ctypes.cast(callback, ctypes.c_void_p)
    io = kernels.function("pc_law_io", ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double,
                          ctypes.c_double, ctypes.POINTER(kernels.Refusal))
    refusal = kernels.Refusal()
    q = joint_motion(*MEASURED)
    for n, reference in enumerate(REFERENCES):
        x = np.array([*q, *reference, *[7.0] * 6])
        assert io(ctypes.addressof(context), x.ctypes.data, n * H, H, refusal) == law.OK
        assert np.array_equal(x[12:], twin.step_with_errors(n * H, *q, *reference, H))
    state = ctrl._buf.copy()
    x = np.array([*q, *REFERENCES[0], *[7.0] * 6])
    x[3] = math.inf
    assert io(ctypes.addressof(context), x.ctypes.data, 0.0, H, refusal) == law.NONFINITE
    assert (refusal.index, refusal.value) == (3, math.inf)
    assert np.array_equal(ctrl._buf, state) and np.all(x[12:] == 7.0)


def test_delay_queue_applies_the_commands_n_samples_late():
    """pc_law_delay with n = 2: the commands applied are those of two samples before (zeros
    first), and the queue keeps the newest last."""
    delayed = np.zeros((2, 4))
    applied = [law.delay(delayed, (k, 10.0 * k, -k, 0.5 * k)) for k in (1.0, 2.0, 3.0, 4.0)]
    assert applied == [(0.0,) * 4, (0.0,) * 4, (1.0, 10.0, -1.0, 0.5), (2.0, 20.0, -2.0, 1.0)]
    assert delayed.tolist() == [[3.0, 30.0, -3.0, 1.5], [4.0, 40.0, -4.0, 2.0]]


@pytest.mark.parametrize("n", [1, 3, 4, 7])
def test_delay_queue_of_any_length_is_a_first_in_first_out_queue(n):
    """pc_law_delay with n rows against a Python deque of n rows started from non-zero rows:
    each call applies the oldest row and queues the command as the newest, every row and
    column of the queue read back after every call.  Catches a shift that moves the wrong
    row into another (the index of a row other than the first two, n >= 3), skips a column
    or drops the oldest at the wrong length."""
    rng = np.random.default_rng(n)
    start = rng.normal(size=(n, 4))
    delayed, queue = start.copy(), [tuple(row) for row in start]
    for _ in range(2 * n + 3):
        command = tuple(rng.normal(size=4))
        queue.append(command)
        assert law.delay(delayed, command) == queue.pop(0)
        assert delayed.tolist() == [list(row) for row in queue]


def inverse_terms_into(p, q, dq, out):
    """:func:`plant.fast5r.inverse_terms` on the kernel's pointers (q, dq of 7, out of INVERSE_SIZE)."""
    as_array = np.ctypeslib.as_array
    fast5r.inverse_terms(p, as_array(q, (7,)), as_array(dq, (7,)), as_array(out, (fast5r.INVERSE_SIZE,)))


def test_layouts_come_from_the_c_structs():
    """The buffers' sizes and fields are the C structs' (one source of offsets)."""
    assert law.STATE_SIZE == 10 + 2 * law.MAX_PREDICT + 4
    assert list(law.STATE) == ["integral", "k", "s_prev", "s", "e", "past", "bias", "offset"]
    assert law.TERMS["Z"] == slice(fast5r.INVERSE_Z, fast5r.INVERSE_Z + 4)   # a prefix of the plant's terms
    assert law.SCRATCH["in"].stop - law.SCRATCH["in"].start == 12 and law.OUT.stop - law.OUT.start == 6
    assert list(law.run_state_words(np.zeros(law.STATE_SIZE + law.PARAMS_SIZE))) == list(range(law.STATE_SIZE))
