"""The derivator's and the trajectories' C kernels (kernels/src/derivator.c, trajectory.c)
against oracles: scipy's filters of the designed chain, exact derivatives, the trajectories'
formulas and finite differences; and their refusals of bad inputs and forged buffers, which
must change nothing and never reach outside the buffer (these tests also run under the
sanitizer build)."""
import ctypes
import math

import numpy as np
import pytest
from scipy import signal

import kernels
from controller import derivators, fastderivator, fasttrajectory, trajectories
from controller.derivators import Derivator
from controller.trajectories import circle, hold, thesis_circle, triangle

T = 1e-3


def chain_oracle(derivator, q):
    """The estimates of (1 - z^-1)/T F_v and (1 - z^-1)/T F_a of that, by scipy's lfilter and
    sosfilt from rest at q[0] (one channel per column)."""
    difference = signal.lfilter([1.0 / T, -1.0 / T], [1.0], q - q[0], axis=0)
    velocity = signal.sosfilt(derivator.velocity_sos, difference, axis=0)
    acceleration = signal.sosfilt(derivator.acceleration_sos,
                                  signal.lfilter([1.0 / T, -1.0 / T], [1.0], velocity, axis=0), axis=0)
    return velocity, acceleration


def stepped(derivator, q):
    derivator.reset(q[0])
    estimates = [derivator.step(sample) for sample in q]
    return np.array([v for v, _ in estimates]), np.array([a for _, a in estimates])


@pytest.mark.parametrize("fc_vel, fc_acc", [(100.0, 40.0), (60.0, 30.0)])
def test_derivator_is_the_designed_filter_chain(fc_vel, fc_acc):
    """Random angles: the kernel's cascade gives scipy's filtering of the designed sections
    (scipy's own direct form, section by section)."""
    rng = np.random.default_rng(27)
    q = np.cumsum(rng.normal(0.0, 0.01, (400, 2)), axis=0) + [0.3, -1.2]
    derivator = Derivator(fc_vel, fc_acc, T)
    velocity, acceleration = stepped(derivator, q)
    expected_velocity, expected_acceleration = chain_oracle(derivator, q)
    np.testing.assert_allclose(velocity, expected_velocity, rtol=0, atol=1e-9 * np.abs(expected_velocity).max())
    np.testing.assert_allclose(acceleration, expected_acceleration, rtol=0,
                               atol=1e-9 * np.abs(expected_acceleration).max())


def test_derivator_gives_the_exact_derivatives_of_a_polynomial_after_the_transient():
    """q = c0 + c1 t + c2 t^2 + c3 t^3: after the transient the velocity is dq/dt at t -
    velocity_delay up to the cubic's curvature term, the acceleration exactly d2q/dt2 at t -
    acceleration_delay (module docstring of controller.derivators)."""
    derivator = Derivator()
    t = np.arange(600) * T
    c0, c1, c2, c3 = 0.4, 1.5, -2.0, 0.7
    q = c0 + c1 * t + c2 * t ** 2 + c3 * t ** 3
    velocity, acceleration = stepped(derivator, q[:, None])
    late = slice(200, None)
    delayed = t[late] - derivator.acceleration_delay
    np.testing.assert_allclose(acceleration[late, 0], 2 * c2 + 6 * c3 * delayed, rtol=0, atol=1e-8)
    parabola = c0 + c1 * t + c2 * t ** 2
    velocity, _ = stepped(Derivator(), parabola[:, None])
    np.testing.assert_allclose(velocity[late, 0], c1 + 2 * c2 * (t[late] - derivator.velocity_delay), rtol=0,
                               atol=1e-9)


def test_derivator_on_a_sine_is_the_frequency_response_after_the_transient():
    """q = A sin(w t): the steady estimates are A |H| sin(w t + arg H) of the chain's frequency
    response (from the sections by scipy's sosfreqz), i.e. the derivative A w cos(w t) with the
    filters' gain and phase."""
    derivator = Derivator()
    f, amplitude = 7.0, 0.8
    t = np.arange(1200) * T
    q = amplitude * np.sin(2 * np.pi * f * t)
    velocity, acceleration = stepped(derivator, q[:, None])
    h_velocity, h_acceleration = derivator.frequency_response([f])
    late = slice(600, None)
    for estimate, response in ((velocity, h_velocity[0]), (acceleration, h_acceleration[0])):
        expected = amplitude * abs(response) * np.sin(2 * np.pi * f * t[late] + np.angle(response))
        np.testing.assert_allclose(estimate[late, 0], expected, rtol=0, atol=1e-7 * np.abs(expected).max())


# --- the derivator kernel called directly -------------------------------------------------------

def _context(buf, scratch, limit=math.inf):
    return derivators._Context(kernels.address(buf), kernels.address(scratch), buf.size, scratch.size, limit)


_IO = kernels.function("pc_derivator_io", ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double,
                       ctypes.c_double, ctypes.POINTER(kernels.Refusal))


def _started_buffer():
    derivator = Derivator()
    derivator.reset([0.2, -0.1])
    for k in range(30):
        derivator.step([0.2 + 1e-3 * k, -0.1 + 2e-3 * k])
    return derivator.buf.copy()


def test_the_io_function_is_the_step_on_two_channels():
    """pc_derivator_io (the compiled loop's call) writes the step's estimates after the inputs."""
    buf = _started_buffer()
    twin = buf.copy()
    holder = Derivator()
    holder.buf = buf
    context = derivators.kernel_context(holder, 10.0)
    x = np.array([0.25, -0.05, 0, 0, 0, 0], dtype=float)
    refusal = kernels.Refusal()
    assert _IO(ctypes.addressof(context), kernels.address(x), 0.0, T, refusal) == 0
    derivator = Derivator()
    derivator.start_at_first_sample(2)
    derivator.buf[:] = twin
    dq, ddq = derivator.step([0.25, -0.05])
    assert x[2:].tolist() == [*dq.tolist(), *ddq.tolist()]
    np.testing.assert_array_equal(buf, derivator.buf)
    x[0] = 11.0
    saved = buf.copy()
    assert _IO(ctypes.addressof(context), kernels.address(x), 0.0, T, refusal) == fastderivator.BAD_INPUT
    assert (refusal.index, refusal.value) == (0, 11.0)
    np.testing.assert_array_equal(buf, saved)


@pytest.mark.parametrize("word, value, index", [
    ("V_STATES", 1000.0, 0), ("V_STATES", 15.5, 0), ("V_STATES", math.nan, 0), ("V_STATES", -3.0, 0),
    ("V_STATES", 0.0, 0), ("V_STATES", 13.0, 0), ("V_STATES", 14.0, 2), ("V_CHANNELS", 3.0, 2),
    ("V_CHANNELS", 1e300, 1), ("V_CHANNELS", 0.0, 1), ("V_VELOCITY_SECTIONS", 6.0, 4),
    ("V_VELOCITY_SECTIONS", -1.0, 4), ("V_VELOCITY_SECTIONS", 0.5, 4), ("V_VELOCITY_SECTIONS", math.nan, 4)])
def test_a_forged_derivator_buffer_is_refused_before_any_access(word, value, index):
    """Sizes that do not fit the buffer's length (a forged FMU state) are refused, naming the
    word, and nothing is read or written beyond the buffer (the sanitizer build checks the
    'beyond'); the buffer is unchanged."""
    buf = _started_buffer()
    buf[getattr(fastderivator, word)] = value
    saved = buf.copy()
    scratch = np.zeros(64 * 64)
    out, refusal = np.zeros(4), kernels.Refusal()
    q = np.array([0.1, 0.2])
    code = derivators._STEP(_context(buf, scratch), kernels.address(q), math.inf, kernels.address(out), refusal)
    assert (code, refusal.index) == (fastderivator.BAD_LAYOUT, index)
    np.testing.assert_array_equal(buf, saved)
    assert not out.any()


@pytest.mark.parametrize("word, change, message", [
    ("V_STATES", 2.0, "length = 56.0"), ("V_STATES", 1e300, r"states = 1e\+300"),
    ("V_CHANNELS", -2.0, "channels = 0.0"), ("V_VELOCITY_SECTIONS", 9.0, "velocity sections = 10.0")])
def test_a_damaged_derivator_buffer_is_a_refusal_record_naming_the_word(word, change, message):
    """Through the Derivator: refused by the kernel, naming the word (and no scratch of the
    forged size is allocated: 1e300 states would not fit in memory)."""
    derivator = Derivator()
    derivator.reset([0.0, 0.0])
    derivator.buf[getattr(fastderivator, word)] += change
    saved = derivator.buf.copy()
    with pytest.raises(kernels.Refused, match=rf"buffer of 56 words is damaged: {message} does not fit") as caught:
        derivator.step([0.0, 0.0])
    assert caught.value.reason == "bad_layout"
    np.testing.assert_array_equal(derivator.buf, saved)


def test_a_small_scratch_is_refused():
    """Catches a derivator kernel that writes past a scratch buffer too small for it."""
    buf = _started_buffer()
    scratch = np.zeros(3)
    out, refusal, q = np.zeros(4), kernels.Refusal(), np.zeros(2)
    code = derivators._STEP(_context(buf, scratch), kernels.address(q), math.inf, kernels.address(out), refusal)
    assert (code, refusal.index, refusal.value) == (fastderivator.BAD_LAYOUT, 3, 3.0)


def test_a_non_finite_estimate_does_not_advance_the_state():
    """A design giving inf (a huge coefficient times an angle): the estimates come out, the
    state and the start flag stay."""
    derivator = Derivator()
    derivator.reset([0.0, 0.0])
    derivator.buf[fastderivator.V_SECTIONS] = 1e308
    saved = derivator.buf.copy()
    dq, _ = derivator.step([1e10, 0.0])
    assert math.isinf(dq[0])
    np.testing.assert_array_equal(derivator.buf, saved)


def test_an_angle_beyond_the_limit_is_a_refusal_record_with_every_angle():
    """Catches a derivator refusal that changes the buffer or names the wrong angle."""
    derivator = Derivator()
    derivator.reset([0.0, 0.0])
    saved = derivator.buf.copy()
    with pytest.raises(kernels.Refused, match=r"angles q = \[0.5, 2.0\] rad must be finite with \|q\| <= 1") as caught:
        derivator.step([0.5, 2.0], limit=1.0)
    assert (caught.value.variable, caught.value.value, caught.value.unit) == ("q2", 2.0, "rad")
    np.testing.assert_array_equal(derivator.buf, saved)


# --- the trajectories ------------------------------------------------------------------------

@pytest.mark.parametrize("trajectory", [thesis_circle(), circle(), circle(frequency=2.5)],
                         ids=["thesis_circle", "bench_circle", "fast_circle"])
def test_a_circle_is_the_analytic_motion(trajectory):
    """x = cx + r cos(phi), phi = phi0 + w t, its velocity and acceleration in closed form."""
    (cx, cy), r, w = trajectory.center, trajectory.radius, trajectory.angular_velocity
    for t in np.linspace(0.0, trajectory.duration - 1e-9, 301):
        phi = trajectory.initial_angle + w * t
        expected = (cx + r * math.cos(phi), cy + r * math.sin(phi), -r * w * math.sin(phi), r * w * math.cos(phi),
                    -r * w * w * math.cos(phi), -r * w * w * math.sin(phi))
        np.testing.assert_allclose(tuple(trajectory(t)), expected, rtol=1e-12, atol=1e-12)


def test_the_triangle_velocity_and_acceleration_are_the_positions_derivatives():
    """Central differences of the positions (step 1e-5 s) give the velocities and of the
    velocities the accelerations, within their truncation error."""
    trajectory, step = triangle(), 1e-5
    for t in np.linspace(2 * step, trajectory.duration - 2 * step, 523):
        before, now, after = trajectory(t - step), trajectory(t), trajectory(t + step)
        for p, v, a in (("x", "dx", "ddx"), ("y", "dy", "ddy")):
            assert (getattr(after, p) - getattr(before, p)) / (2 * step) == pytest.approx(getattr(now, v), abs=1e-6)
            assert (getattr(after, v) - getattr(before, v)) / (2 * step) == pytest.approx(getattr(now, a), abs=1e-4)


_SAMPLE = kernels.function("pc_trajectory_sample", ctypes.c_int, ctypes.c_void_p, ctypes.c_long, ctypes.c_double,
                           ctypes.c_void_p, ctypes.POINTER(kernels.Refusal))


def _sample(buf, t, words=None):
    out, refusal = np.zeros(6), kernels.Refusal()
    code = _SAMPLE(kernels.address(buf), buf.size if words is None else words, t, kernels.address(out), refusal)
    return code, refusal, out


@pytest.mark.parametrize("word, value", [
    ("T_VERTICES", 4.0), ("T_VERTICES", 2.5), ("T_VERTICES", 0.0), ("T_VERTICES", math.nan),
    ("T_CYCLES", math.nan), ("T_CYCLES", 1e300), ("T_SIDE_TIME", 0.0), ("T_SIDE_TIME", math.nan),
    ("T_KIND", 7.0)])
def test_a_forged_polygon_is_refused_naming_its_word(word, value):
    """Catches a trajectory kernel that trusts a forged buffer word (count, kind, times)."""
    buf = triangle().buf.copy()
    buf[getattr(fasttrajectory, word)] = value
    code, refusal, out = _sample(buf, 1.0)
    assert code == fasttrajectory.BAD_LAYOUT
    assert refusal.index == getattr(fasttrajectory, word)
    assert not out.any()



@pytest.mark.parametrize("word, value", [("T_VERTICES", 2.5), ("T_CYCLES", math.nan), ("T_KIND", 7.0)])
def test_a_forged_trajectory_is_refused_in_python_with_the_whole_record(word, value):
    """Catches the damaged-buffer refusal's record read back wrong through the Python call: its
    reason, its (empty) variable and unit, the value, the time, and the message word for word
    with the word's index."""
    trajectory = triangle()
    trajectory.buf[getattr(fasttrajectory, word)] = value
    with pytest.raises(kernels.Refused) as caught:
        trajectory(0.75)
    record = caught.value.record()
    assert (record["reason"], record["variable"], record["unit"], caught.value.time) == ("bad_layout", "", "", 0.75)
    assert record["value"] == value or math.isnan(value) and math.isnan(record["value"])
    assert str(caught.value) == (f"the trajectory's buffer is damaged: word {getattr(fasttrajectory, word)} = "
                                 f"{value!r} does not fit it")


triangle_ = triangle()


@pytest.mark.parametrize("trajectory", [circle(), triangle_, hold()], ids=["circle", "triangle", "hold"])
def test_a_short_trajectory_buffer_is_refused(trajectory):
    """Catches a trajectory kernel that reads past the end of a short buffer."""
    buf = trajectory.buf
    assert _sample(buf, 0.5)[0] == 0
    code, refusal, _ = _sample(buf, 0.5, buf.size - 1)
    if trajectory is triangle_:     # its vertices no longer fit
        assert (code, refusal.index) == (fasttrajectory.BAD_LAYOUT, fasttrajectory.T_VERTICES)
    else:
        assert (code, refusal.index, refusal.value) == (fasttrajectory.BAD_LAYOUT, -1, buf.size - 1)


@pytest.mark.parametrize("t", [-1e-9, math.nan, -math.inf])
def test_a_time_before_zero_is_a_refusal_record(t):
    """Catches a trajectory sampled at negative or NaN time, or refused with the wrong record."""
    with pytest.raises(kernels.Refused, match="trajectory time must be >= 0 s") as caught:
        circle()(t)
    record = caught.value.record()
    assert (record["variable"], record["unit"], record["reason"]) == ("t", "s", "bad_time")
    assert record["value"] == t or math.isnan(t)


def test_the_trajectory_io_function_gives_the_reference_at_the_steps_end():
    """Catches a trajectory I/O function that gives the reference at the step's start."""
    trajectory = triangle()
    context = trajectories.kernel_context(trajectory)
    io = kernels.function("pc_trajectory_io", ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double,
                          ctypes.c_double, ctypes.POINTER(kernels.Refusal))
    x = np.zeros(6)
    assert io(ctypes.addressof(context), kernels.address(x), 1.2, 1e-3, kernels.Refusal()) == 0
    assert x.tolist() == list(trajectory(1.2 + 1e-3))


@pytest.mark.parametrize("words", [1, 2, fasttrajectory.T_VERTICES])
def test_a_polygon_buffer_shorter_than_its_header_is_refused_with_its_length(words):
    """A polygon's buffer cut inside its header (kind, times, count): BAD_LAYOUT naming no word
    (index -1) and the length given, nothing written.  Catches the header check's record
    filled like a forged word's, or the header read past the length."""
    code, refusal, out = _sample(triangle().buf.copy(), 0.5, words)
    assert (code, refusal.index, refusal.value) == (fasttrajectory.BAD_LAYOUT, -1, float(words))
    assert not out.any()


@pytest.mark.parametrize("words", [0, 1, fastderivator.V_RATE - 1])
def test_a_derivator_buffer_shorter_than_its_header_is_refused_with_its_length(words):
    """A buffer length that does not reach past the header (the sizes and flags before the data):
    BAD_LAYOUT naming the length (index 2) with that length, before any word is read; nothing
    written."""
    buf = _started_buffer()
    saved = buf.copy()
    scratch = np.zeros(64 * 64)
    context = derivators._Context(kernels.address(buf), kernels.address(scratch), words, scratch.size, math.inf)
    out, refusal, q = np.zeros(4), kernels.Refusal(), np.array([0.1, 0.2])
    code = derivators._STEP(context, kernels.address(q), math.inf, kernels.address(out), refusal)
    assert (code, refusal.index, refusal.value) == (fastderivator.BAD_LAYOUT, 2, float(words))
    np.testing.assert_array_equal(buf, saved)
    assert not out.any()


def test_the_io_function_refuses_a_one_channel_derivator_naming_its_channels():
    """pc_derivator_io writes two channels' estimates (x = [q1, q2 | dq1, dq2, ddq1, ddq2]): a
    buffer of one channel is refused as BAD_LAYOUT naming the channels word (index 1) and its
    value 1, the buffer and x unchanged; a context without a buffer is refused naming the
    length (index 2)."""
    one = Derivator()
    one.reset([0.3])
    assert one.buf[fastderivator.V_CHANNELS] == 1.0
    saved = one.buf.copy()
    scratch = np.zeros(64)
    x = np.array([0.25, -0.05, 7.0, 7.0, 7.0, 7.0])
    refusal = kernels.Refusal()
    context = _context(one.buf, scratch)
    assert _IO(ctypes.addressof(context), kernels.address(x), 0.0, T, refusal) == fastderivator.BAD_LAYOUT
    assert (refusal.index, refusal.value) == (1, 1.0)
    np.testing.assert_array_equal(one.buf, saved)
    assert x.tolist() == [0.25, -0.05, 7.0, 7.0, 7.0, 7.0]
    empty = derivators._Context(None, kernels.address(scratch), 5, scratch.size, math.inf)
    assert _IO(ctypes.addressof(empty), kernels.address(x), 0.0, T, refusal) == fastderivator.BAD_LAYOUT
    assert (refusal.index, refusal.value) == (2, 5.0)


@pytest.mark.parametrize("channel", [0, 1])
def test_an_angle_at_the_limit_is_taken_and_one_double_beyond_is_refused_naming_its_channel(channel):
    """The derivator's input check reads |q| <= limit (controller/derivators.py's message): an
    angle of magnitude exactly the limit is taken, either sign, and the next double beyond it
    is refused as BAD_INPUT naming that channel and its value, the buffer unchanged."""
    limit = 0.75
    for sign in (1.0, -1.0):
        buf = _started_buffer()
        out, refusal = np.zeros(4), kernels.Refusal()
        q = np.array([0.1, -0.2])
        q[channel] = sign * limit
        code = derivators._STEP(_context(buf, np.zeros(64)), kernels.address(q), limit, kernels.address(out), refusal)
        assert code == 0
        q[channel] = sign * np.nextafter(limit, np.inf)
        saved = buf.copy()
        code = derivators._STEP(_context(buf, np.zeros(64)), kernels.address(q), limit, kernels.address(out), refusal)
        assert (code, refusal.index, refusal.value) == (fastderivator.BAD_INPUT, channel, q[channel])
        np.testing.assert_array_equal(buf, saved)
