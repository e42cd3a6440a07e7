"""The position law's delay compensation (kernels/src/law.c ``pc_law_predict``, the law's
``predict``; docs/contract.md "Delay compensation") against a double integrator integrated
here, and the option off against the law as it was.
"""
import numpy as np
import pytest

from controller import law
from controller.kinematics import Kinematics
from controller.position import PositionController
from controller.strategies import get_strategy
from plant import get_preset

H = 1e-3


def double_integrator(accelerations, q0, v0, h=H):
    """Exact (q, v) at every period's start of a double integrator whose acceleration is
    ``accelerations[k]`` (rows of 2) over period k: q += h v + h^2 a / 2, v += h a."""
    q, v = [np.array(q0, float)], [np.array(v0, float)]
    for a in accelerations:
        q.append(q[-1] + h * v[-1] + 0.5 * h * h * a)
        v.append(v[-1] + h * a)
    return np.array(q), np.array(v)


@pytest.mark.parametrize("a, b", [(2, 3), (1, 1), (3, 0), (0, 2), (4, 2), (8, 8)])
def test_prediction_is_the_double_integrators_state_at_the_commands_time(a, b):
    """Commands c_k, a plant that follows c_k - d (a constant part d it does not follow, given
    as the bias): from the angle a periods and the rate b periods before period k and the
    commands since, the prediction is the state at k to rounding.  Catches the commands taken
    in the wrong order or shifted by one, a missing h^2/2 term, the bias with the wrong sign,
    and the rates not brought to the angles' time (a > b goes back)."""
    rng = np.random.default_rng(a * 10 + b)
    commands = rng.normal(0.0, 50.0, (30, 2))
    d = np.array([3.0, -7.0])
    q, v = double_integrator(commands - d, (0.3, 2.1), (-0.4, 0.9))
    for k in range(10, 30):
        past = commands[k - 1::-1][:max(a, b, 1)]          # newest first: over [k-1, k], [k-2, k-1], ...
        measured = (*q[k - a], *v[k - b])
        joint = law.predict(measured, past, d, a, b, H)
        np.testing.assert_allclose(joint, (*q[k], *v[k]), rtol=0, atol=1e-12)
    if a or b:   # the prediction is not the measurement: the test can fail
        assert not np.allclose(law.predict(measured, past, d, a, b, H), measured, atol=1e-6)


def _run(delay_compensation, steps=40):
    """PDx, TCMDq samples on a pose moving off the circle: the outputs and the law's state."""
    from controller.trajectories import get_trajectory

    bench, circle = get_preset("bench"), get_trajectory("circle")
    kin = Kinematics(bench)
    rows = []
    for name in ("PDx", "TCMDq"):
        c = PositionController(bench, get_strategy(name), model="exact", delay_compensation=delay_compensation)
        for k in range(steps):
            t = k * H
            r = circle(t)
            angles = kin.inverse(r.x + 0.001 * np.sin(30 * t), r.y)
            rows.append(c.step_with_errors(t, angles[0], angles[2], 0.2 * np.cos(9 * t), -0.1, 0.5, 0.3,
                                           r.x, r.y, r.dx, r.dy, r.ddx, r.ddy))
    return np.array(rows)


def test_compensation_changes_the_commands_and_zero_is_the_law_without_it():
    """(0, 0) is the law without compensation (the default), bit for bit; (2, 3) changes the
    commands once it has commanded.  Catches an option that is always on, or never on."""
    off, default, on = _run((0, 0)), _run(PositionController.__init__.__defaults__[-1]), _run((2, 3))
    assert np.array_equal(off, default)
    assert not np.allclose(on[5:], off[5:])


@pytest.mark.parametrize("value", [(9, 0), (0, -1), (1.5, 1), (True, 0), (2,)])
def test_compensation_out_of_range_is_refused_by_name(value):
    """Catches a compensation beyond the kept commands (which would read past the state)."""
    with pytest.raises(ValueError, match="delay_compensation"):
        PositionController(get_preset("bench"), get_strategy("PDq"), delay_compensation=value)


@pytest.mark.parametrize("name", ["PDx", "PDq", "PDMDx", "PDMDq"])
def test_the_kept_acceleration_and_offset_are_the_commands_in_joint_space(name):
    """After a sample of a PD model (H = m* 1, h = 0: the command a' = tau / m* in joint space,
    J^-T tau / m* in task space) the law keeps q'' = J^-1 (a' - beta) (joint space: a' itself)
    as its newest command, and as the offset the low-passed feedback plus the integral I in
    joints, alpha J^-1 (a' - r''_d - I) + J^-1 I (alpha = h lam / (1 + h lam); joint space:
    J = 1, r''_d the law's joint reference), each computed here from the outputs, the integral
    and J, beta of the task state at the pose the law acted on.  The joints move (beta != 0),
    the reference accelerates (r''_d != 0) and the MD strategies integrate (I != 0), so a
    dropped or sign-flipped beta, r''_d, I or J^-1 changes a kept value.  Catches the
    prediction's inputs (kernels/src/law.c ``remember``) computed wrongly, which the
    predictions of later samples only read."""
    bench = get_preset("bench")
    kin = Kinematics(bench)
    c = PositionController(bench, get_strategy(name), model="exact", delay_compensation=(1, 1))
    angles = kin.inverse(0.01, 0.12)
    ddr_d = np.array([0.7, -0.4])
    out = c.step_with_errors(0.0, angles[0], angles[2], 1.3, -0.9, 0.0, 0.0, 0.012, 0.118, 0.05, -0.02, *ddr_d)
    tau, integral = np.array(out[:2]), np.array(c.integral)
    buf = c._buf
    m_star, lam = buf[law.BUF["m_star"]][0], buf[law.BUF["lam"]][0]
    q1, q2, dq1, dq2 = c._scratch[law.JOINT]
    *_, J, beta = kin.task_state(q1, q2, dq1, dq2, 0.0, 0.0)
    J, beta = np.array(J).reshape(2, 2), np.array(beta)
    assert np.max(np.abs(beta)) > 0.1 and abs(dq1) > 1.0
    assert (np.max(np.abs(integral)) > 1e-3) == ("MD" in name)
    if name.endswith("x"):
        command = np.linalg.solve(J.T, tau) / m_star
        kept = np.linalg.solve(J, command - beta)
        offset = np.linalg.solve(J, (H * lam * (command - ddr_d - integral)) / (1.0 + H * lam) + integral)
    else:   # the reference in joint space as the law converted it (its own checks are elsewhere)
        command = tau / m_star
        kept = command
        offset = H * lam * (command - c._scratch[law.SCRATCH["rd"]][4:6] - integral) / (1.0 + H * lam) + integral
    past = buf[law.STATE["past"]]
    np.testing.assert_allclose(past[:2], kept, rtol=1e-10, atol=1e-9)
    np.testing.assert_array_equal(past[2:], 0.0)
    np.testing.assert_allclose(buf[law.STATE["offset"]], offset, rtol=1e-10, atol=1e-9)
    assert np.max(np.abs(kept)) > 1.0 and np.max(np.abs(offset)) > 1e-3


@pytest.mark.parametrize("a, b", [(2, 3), (3, 1)])
def test_the_kept_commands_shift_one_row_a_sample_newest_first(a, b):
    """With max(a, b) = 3 rows kept, after each of four PDq samples (a' = tau / m*, joint space)
    the rows are the last three commands newest first, the rows beyond them zero until filled
    and the oldest dropped after the third.  Catches the history's shift (the memmove in
    kernels/src/law.c ``remember``) moving fewer or more bytes than the rows kept, or none."""
    bench = get_preset("bench")
    c = PositionController(bench, get_strategy("PDq"), model="exact", delay_compensation=(a, b))
    m_star, rows = c._buf[law.BUF["m_star"]][0], 3
    angles, commands = Kinematics(bench).inverse(0.01, 0.12), []
    for k in range(4):
        out = c.step_with_errors(k * H, angles[0] + 1e-3 * k, angles[2] - 2e-3 * k, 1.3, -0.9, 0.0, 0.0,
                                 0.012, 0.118, 0.05, -0.02, 0.7, -0.4)
        commands.insert(0, np.array(out[:2]) / m_star)
        past = c._buf[law.STATE["past"]].reshape(-1, 2)
        expected = np.zeros_like(past)
        expected[:min(len(commands), rows)] = commands[:rows]
        np.testing.assert_allclose(past, expected, rtol=1e-12, atol=1e-12)
    assert len({tuple(np.round(x, 6)) for x in commands}) == 4       # four different commands


@pytest.mark.parametrize("a, b", [(3, 2), (2, 3), (4, 0), (1, 1)])
def test_predict_refuses_a_past_shorter_than_max_a_b_rows_and_takes_exactly_that_many(a, b):
    """``pc_law_predict`` takes no length: it reads max(a, b) rows of 2 commands, so the
    Python binding is the only guard.  One row short (or one value short) is refused, naming
    the rows needed; exactly max(a, b) rows is the double integrator's state (the test
    above).  Catches the length bound computed wrongly (2 / max instead of 2 * max), which
    lets the kernel read past the array."""
    rows = max(a, b)
    commands = np.full((rows + 1, 2), 5.0)
    measured, d = (0.1, -0.2, 0.3, 0.4), (0.0, 0.0)
    for short in (commands[:rows - 1], commands.reshape(-1)[:2 * rows - 1]):
        with pytest.raises(ValueError, match=rf"past of {len(short.reshape(-1)) // 2} rows for "
                                             rf"a = {a}, b = {b}: need 4, 2 and max\(a, b\) rows"):
            law.predict(measured, short, d, a, b, H)
    q, v = double_integrator(commands[:rows], measured[:2], measured[2:])
    joint = law.predict(measured, commands[:rows], d, rows, rows, H)
    np.testing.assert_allclose(joint, (*q[rows], *v[rows]), rtol=0, atol=1e-12)


@pytest.mark.parametrize("measured, bias", [((0.0,) * 3, (0.0, 0.0)), ((0.0,) * 5, (0.0, 0.0)),
                                            ((0.0,) * 4, (0.0,)), ((0.0,) * 4, (0.0,) * 3)])
def test_predict_refuses_a_measurement_not_of_4_or_a_bias_not_of_2(measured, bias):
    """The measured state is (q1, q2, dq1, dq2) and the bias one acceleration per joint: any
    other length is refused before the kernel reads it."""
    with pytest.raises(ValueError, match=r"predict: measured \(\d\,\), bias \(\d\,\)"):
        law.predict(measured, np.zeros((2, 2)), bias, 1, 1, H)


@pytest.mark.parametrize("a, b", [(3, 0), (2, 5), (0, 4)])
def test_the_task_reference_is_carried_a_periods_ahead_along_its_own_derivatives(a, b):
    """In task space the law acts on the reference at the commands' time, a periods (A = a h)
    after the sample: (x_d + A dx_d + A^2 ddx_d / 2, dx_d + A ddx_d, ddx_d), y alike (the Taylor
    series of a constant-acceleration reference, written here); the rates' delay b does not
    move it, and a = 0 leaves it as given, bit for bit.  The acceleration is large (50 m/s^2)
    so that its A^2 / 2 term (1e-4 m at a = 2) is far above the check's tolerance: at the
    bench's small references it is the term a dropped or sign-flipped one hides in (training
    4302 [0])."""
    bench = get_preset("bench")
    c = PositionController(bench, get_strategy("PDx"), model="exact", delay_compensation=(a, b))
    angles = Kinematics(bench).inverse(0.01, 0.12)
    reference = np.array([0.012, 0.118, 0.4, -0.3, 50.0, -30.0])
    c.step_with_errors(0.0, angles[0], angles[2], 0.3, -0.2, 0.0, 0.0, *reference)
    ahead = a * H
    position, rate, acceleration = reference[:2], reference[2:4], reference[4:]
    expected = np.concatenate([position + ahead * rate + 0.5 * ahead ** 2 * acceleration,
                               rate + ahead * acceleration, acceleration])
    rd = c._scratch[law.SCRATCH["rd"]]
    if a == 0:
        np.testing.assert_array_equal(rd, reference)
    else:
        np.testing.assert_allclose(rd, expected, rtol=1e-14, atol=1e-17)
        assert np.max(np.abs(0.5 * ahead ** 2 * acceleration)) > 5e-5   # 1e4 times the tolerance
