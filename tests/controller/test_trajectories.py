"""Tests of controller.trajectories against the thesis' formulas (7.18, 7.23-7.28)."""

import dataclasses
import math

import numpy as np
import pytest

import kernels
from controller.trajectories import (PRESET_CYCLES, SMOOTHSTEP_COEFFICIENTS, SMOOTHSTEP_SLOPE_COEFFICIENTS,
                                    TRAJECTORY_KINDS, ReferenceSample, from_parameters, get_trajectory)

STEP = 1e-6
"""Finite-difference step, s."""
X1, X2, X3 = (-0.002, 0.108), (0.050, 0.258), (-0.050, 0.258)
"""Triangle vertices (7.24-7.26), m."""


def thesis_circle_formula(t):
    """(7.18), as printed."""
    return 0.07 * math.cos(2 * math.pi * t), 0.17 + 0.07 * math.sin(2 * math.pi * t)


def bench_circle_formula(t):
    """(7.23), as printed."""
    return -0.05 * math.sin(2 * math.pi * t), 0.158 - 0.05 * math.cos(2 * math.pi * t)


def triangle_formula(t):
    """(7.27) on the sides I: x1->x2, II: x2->x3, III: x3->x1, 0.75 s each, 2 cycles, then x1."""
    if t >= 4.5:
        return X1
    side = int(t / 0.75)
    start, end = [(X1, X2), (X2, X3), (X3, X1)][side % 3]
    tau = t / 0.75 - side
    s = 35 * tau**4 - 84 * tau**5 + 70 * tau**6 - 20 * tau**7
    return tuple(p0 + (pf - p0) * s for p0, pf in zip(start, end))


def times(duration, count=997):
    """Sample times across the motion, away from 0 so that central differences fit."""
    return np.linspace(2 * STEP, duration - 2 * STEP, count)


def central_difference(trajectory, t, fields):
    """Central differences of the named fields of the trajectory at t."""
    before, after = trajectory(t - STEP), trajectory(t + STEP)
    return np.array([(getattr(after, name) - getattr(before, name)) / (2 * STEP) for name in fields])


@pytest.mark.parametrize(
    "kind, formula",
    [("thesis_circle", thesis_circle_formula), ("circle", bench_circle_formula), ("triangle", triangle_formula)],
)
def test_positions_follow_thesis_formulas(kind, formula):
    """Catches a trajectory position that differs from the thesis' formula at any time."""
    trajectory = get_trajectory(kind)
    for t in np.linspace(0.0, trajectory.duration, 4001)[:-1]:
        sample = trajectory(t)
        assert np.allclose((sample.x, sample.y), formula(t), rtol=0, atol=1e-12), t


@pytest.mark.parametrize("kind", ["thesis_circle", "circle", "triangle"])
def test_derivatives_match_central_differences(kind):
    """Catches a trajectory velocity or acceleration that is not the derivative of its position."""
    trajectory = get_trajectory(kind)
    for t in times(trajectory.duration):
        sample = trajectory(t)
        assert np.allclose((sample.dx, sample.dy), central_difference(trajectory, t, ("x", "y")), rtol=0, atol=1e-8), t
        assert np.allclose((sample.ddx, sample.ddy), central_difference(trajectory, t, ("dx", "dy")), rtol=0, atol=1e-7), t


def jerk(trajectory, t):
    """Difference of the acceleration around t (one-sided at t = 0), m/s^3."""
    lower = max(t - STEP, 0.0)
    before, after = trajectory(lower), trajectory(t + STEP)
    return (np.array(after[4:]) - np.array(before[4:])) / (t + STEP - lower)


def test_triangle_vertices_have_zero_velocity_acceleration_and_jerk():
    """Catches a triangle that does not stop with zero velocity, acceleration and jerk at a vertex."""
    trajectory = get_trajectory("triangle")
    peak_jerk = max(np.abs(jerk(trajectory, t)).max() for t in np.linspace(0.01, 0.74, 147))
    assert peak_jerk > 10.0
    for t, vertex in zip(0.75 * np.arange(7), [X1, X2, X3, X1, X2, X3, X1]):
        sample = trajectory(t)
        assert np.allclose((sample.x, sample.y), vertex, rtol=0, atol=1e-15), t
        assert np.allclose(sample[2:], 0.0, rtol=0, atol=1e-12), t
        assert np.abs(jerk(trajectory, t)).max() < 1e-4 * peak_jerk, t


def test_circle_stops_suddenly_and_continuously():
    """Catches a circle whose position jumps at its end, or that keeps moving after it."""
    trajectory = get_trajectory("circle")
    assert trajectory.duration == 8.0
    just_before, at_stop, later = trajectory(8.0 - 1e-9), trajectory(8.0), trajectory(9.3)
    assert np.allclose((at_stop.x, at_stop.y), bench_circle_formula(8.0), rtol=0, atol=1e-15)
    assert np.allclose((just_before.x, just_before.y), (at_stop.x, at_stop.y), rtol=0, atol=1e-9)
    assert math.hypot(just_before.dx, just_before.dy) == pytest.approx(0.05 * 2 * math.pi)
    assert at_stop[:2] == later[:2] and at_stop[2:] == later[2:] == (0.0, 0.0, 0.0, 0.0)


def test_triangle_holds_first_vertex_after_two_cycles():
    """Catches a triangle that does not hold its first vertex after its two cycles."""
    trajectory = get_trajectory("triangle")
    assert trajectory.duration == pytest.approx(4.5)
    assert trajectory(4.5) == trajectory(20.0) == ReferenceSample(*X1, 0.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize(
    "kind, start",
    [("thesis_circle", (0.07, 0.17)), ("circle", X1), ("triangle", X1), ("hold", X1)],
)
def test_start_points_are_those_of_the_spec(kind, start):
    """Catches a trajectory's start point other than the spec's."""
    assert get_trajectory(kind).start_point == pytest.approx(start, abs=1e-15)


def test_reference_starts_at_the_start_point_where_the_thesis_says_so():
    """Catches a reference whose sample at t = 0 is not the start point."""
    thesis = get_trajectory("thesis_circle")(0.0)
    assert (thesis.x, thesis.y) == pytest.approx((0.07, 0.17), abs=1e-15)
    assert get_trajectory("triangle")(0.0) == ReferenceSample(*X1, 0.0, 0.0, 0.0, 0.0)


def test_hold_is_constant_at_rest():
    """Catches a hold trajectory that moves or has a non-zero derivative."""
    trajectory = get_trajectory("hold", x=0.01, y=0.2)
    for t in (0.0, 1.0, 100.0):
        assert trajectory(t) == ReferenceSample(0.01, 0.2, 0.0, 0.0, 0.0, 0.0)


def test_factory_passes_parameters_and_names_unknown_kinds():
    """Catches a factory dropping parameters or refusing an unknown kind without listing the known."""
    assert get_trajectory("circle", cycles=3).duration == 3.0
    assert get_trajectory("triangle", side_time=0.5, cycles=1).duration == pytest.approx(1.5)
    with pytest.raises(ValueError, match="unknown trajectory kind 'square'") as error:
        get_trajectory("square")
    assert all(kind in str(error.value) for kind in TRAJECTORY_KINDS)


def test_the_smoothstep_coefficients_are_the_polynomial_of_7_27_and_its_slope():
    """Catches a wrong coefficient of s(τ) or s'(τ) as the C kernels get them (the polygon's and
    the balanced mechanisms' trajectories): ascending powers against (7.27) written out,
    s = 35τ⁴ − 84τ⁵ + 70τ⁶ − 20τ⁷, and its derivative term by term."""
    for tau in (0.0, 0.1, 0.37, 0.5, 0.81, 1.0):
        s = 35 * tau ** 4 - 84 * tau ** 5 + 70 * tau ** 6 - 20 * tau ** 7
        ds = 140 * tau ** 3 - 420 * tau ** 4 + 420 * tau ** 5 - 140 * tau ** 6
        value = np.polynomial.polynomial.polyval(tau, SMOOTHSTEP_COEFFICIENTS)
        slope = np.polynomial.polynomial.polyval(tau, SMOOTHSTEP_SLOPE_COEFFICIENTS)
        assert (value, slope) == pytest.approx((s, ds), rel=1e-12, abs=1e-15)


def test_a_circle_turning_backwards_or_not_at_all_is_refused():
    """Catches a circle built with a zero, negative or infinite frequency."""
    for frequency in (0.0, -1.0, math.inf):
        with pytest.raises(ValueError, match=f"frequency = {frequency!r} Hz must be > 0"):
            get_trajectory("circle", frequency=frequency)


def test_fmu_parameters_give_the_kinds_trajectory_and_name_a_bad_one():
    """from_parameters (the Trajectory FMU's parameters): the preset cycles keep each kind's
    default (thesis_circle 2, circle 8, triangle 2 rounds); a parameter a kind does not use is
    ignored, even when it would be refused; a used one below its range is refused by name."""
    durations = {"thesis_circle": 2.0, "circle": 8.0, "triangle": 4.5}
    unused = {"thesis_circle": {"side_time": -1.0, "frequency": -1.0}, "circle": {"side_time": -1.0},
              "triangle": {"frequency": -1.0}}
    for kind, duration in durations.items():
        assert from_parameters(kind).duration == pytest.approx(duration)
        assert from_parameters(kind, PRESET_CYCLES, **unused[kind]) == get_trajectory(kind)
        assert from_parameters(kind, np.int64(PRESET_CYCLES)) == get_trajectory(kind)   # e.g. from a sweep's array
    assert from_parameters("circle", 3, frequency=2.0) == get_trajectory("circle", cycles=3, frequency=2.0)
    assert from_parameters("triangle", 1, side_time=0.5) == get_trajectory("triangle", side_time=0.5, cycles=1)
    assert from_parameters("hold", 0, x_hold=0.01, y_hold=0.2) == get_trajectory("hold", x=0.01, y=0.2)
    assert from_parameters("hold").start_point == X1
    for kind, kwargs, text in (("circle", {"cycles": 0}, "parameter cycles = 0 must be >= 1"),
                               ("triangle", {"cycles": -2}, "parameter cycles = -2 must be >= 1"),
                               ("circle", {"frequency": 0.0}, "parameter frequency = 0.0 Hz must be > 0"),
                               ("circle", {"frequency": -2.0}, "parameter frequency = -2.0 Hz must be > 0"),
                               ("triangle", {"side_time": 0.0}, "parameter side_time = 0.0 s must be > 0"),
                               ("triangle", {"side_time": -0.5}, "parameter side_time = -0.5 s must be > 0"),
                               ("square", {}, "parameter kind: unknown trajectory kind 'square'")):
        with pytest.raises(ValueError, match=text):
            from_parameters(kind, **kwargs)


def test_trajectories_are_immutable_and_reject_negative_time():
    """Catches a trajectory that can be changed after creation or sampled at negative time."""
    trajectory = get_trajectory("circle")
    with pytest.raises(dataclasses.FrozenInstanceError):
        trajectory.radius = 0.1
    with pytest.raises(ValueError, match="time"):
        trajectory(-0.001)


@pytest.mark.parametrize("frequency", [0.25, 1.5])
def test_circle_at_another_frequency_is_the_same_circle_in_scaled_time(frequency):
    """circle(frequency=f) at t is circle() at f t, with velocity x f and acceleration x f^2;
    8 turns last 8/f s, then the same stop point."""
    fast, slow = get_trajectory("circle", frequency=frequency), get_trajectory("circle")
    for t in np.linspace(0.0, 7.9 / frequency, 37):
        a, b = fast(t), slow(frequency * t)
        np.testing.assert_allclose([a.x, a.y], [b.x, b.y], atol=1e-15)
        np.testing.assert_allclose([a.dx, a.dy], [frequency * b.dx, frequency * b.dy], atol=1e-14)
        np.testing.assert_allclose([a.ddx, a.ddy], [frequency ** 2 * b.ddx, frequency ** 2 * b.ddy], atol=1e-13)
    assert fast.duration == pytest.approx(8.0 / frequency)
    np.testing.assert_allclose(fast(9.0 / frequency)[:2], slow(9.0)[:2], atol=1e-15)
    with pytest.raises(ValueError, match="frequency = 0.0 Hz must be > 0"):
        get_trajectory("circle", frequency=0.0)


@pytest.mark.parametrize("kind", ["circle", "triangle", "hold"])
def test_sample_values_are_the_reference_sample_in_field_order(kind):
    """The FMU's fast path (buffers reused, no object per sample) gives the fields of
    ``trajectory(t)`` in order, and refuses a negative time like it."""
    from controller.trajectories import sample_buffers, sample_values

    trajectory, buffers = from_parameters(kind, PRESET_CYCLES), sample_buffers()
    for t in (0.0, 0.123, 0.8, 1.7, 100.0):
        assert sample_values(trajectory, t, *buffers) == list(trajectory(t))
    with pytest.raises(ValueError, match="trajectory time must be >= 0 s"):
        sample_values(trajectory, -1.0, *buffers)


def test_a_sampled_trajectory_is_freed_when_dropped_and_its_samples_stay_its_own():
    """Catches a sampler cache (``_sampler``) that keeps the trajectory itself alive (a leak: an
    FMU instance's trajectory would never be freed, and its id could not be reused safely) or
    that gives one trajectory's samples for another's."""
    import gc
    import weakref

    from controller.trajectories import sample_buffers, sample_values

    buffers = sample_buffers()
    circle, triangle = from_parameters("circle", PRESET_CYCLES), from_parameters("triangle", PRESET_CYCLES)
    for t in (0.3, 0.6):
        assert sample_values(circle, t, *buffers) == list(circle(t))
        assert sample_values(triangle, t, *buffers) == list(triangle(t))
    alive = weakref.ref(circle)
    del circle
    gc.collect()
    assert alive() is None


@pytest.mark.parametrize("kind", ["circle", "triangle", "hold"])
def test_a_negative_time_is_refused_with_the_whole_record(kind):
    """Both call paths (``trajectory(t)`` and the FMU's ``sample_values``) refuse t < 0 with
    the record read back field by field: reason bad_time, variable t, unit s, the value and
    the time, and the message word for word.  Catches the reason's variable and unit swapped
    or wrong (the message alone would not show it)."""
    from controller.trajectories import sample_buffers, sample_values

    trajectory = from_parameters(kind, PRESET_CYCLES)
    for call in (trajectory, lambda t: sample_values(trajectory, t, *sample_buffers())):
        with pytest.raises(kernels.Refused) as caught:
            call(-0.25)
        record = caught.value.record()
        assert (record["reason"], record["variable"], record["unit"], record["value"], caught.value.time) == \
            ("bad_time", "t", "s", -0.25, -0.25)
        assert str(caught.value) == "trajectory time must be >= 0 s, got -0.25"


def test_the_sampler_cache_keeps_one_binding_per_live_trajectory_and_drops_it_with_the_trajectory():
    """``_sampler``'s cache (controller/trajectories.py): a trajectory sampled again with the same
    buffers reuses its binding, new buffers rebind it (and sample into them), and the entry
    leaves the cache when the trajectory is collected, while another trajectory's stays.
    Catches a finalizer tied to the buffer (which the cache itself keeps alive, so it never
    runs) or registered only when the trajectory is already cached (never for one sampled once),
    or a cache that never hits."""
    import gc

    from controller import trajectories as tr

    circle, triangle = from_parameters("circle", PRESET_CYCLES), from_parameters("triangle", PRESET_CYCLES)
    expected = {(name, t): list(trajectory(t)) for name, trajectory in (("circle", circle), ("triangle", triangle))
                for t in (0.3, 0.6)}                  # each call here binds buffers of its own: before the checks
    first, second = tr.sample_buffers(), tr.sample_buffers()
    assert tr.sample_values(circle, 0.3, *first) == expected["circle", 0.3]
    assert tr.sample_values(triangle, 0.3, *first) == expected["triangle", 0.3]
    bound = tr._SAMPLERS[id(circle)][3]
    assert all(a is b for a, b in zip(tr._SAMPLERS[id(circle)][:3], (circle.buf, *first)))
    assert tr._sampler(circle, circle.buf, *first) is bound                 # the same buffers: a hit
    assert tr.sample_values(circle, 0.6, *second) == expected["circle", 0.6]   # new buffers: rebound
    assert tr._SAMPLERS[id(circle)][1] is second[0] and tr._SAMPLERS[id(circle)][3] is not bound
    assert list(second[0]) == expected["circle", 0.6] and list(first[0]) == expected["triangle", 0.3]
    key, kept = id(circle), id(triangle)
    del circle, bound
    gc.collect()
    assert key not in tr._SAMPLERS and kept in tr._SAMPLERS
    del triangle
    gc.collect()
    assert kept not in tr._SAMPLERS
    once = from_parameters("hold", PRESET_CYCLES)            # sampled once, never again: its one binding
    tr.sample_values(once, 0.1, *first)
    key = id(once)
    assert key in tr._SAMPLERS
    del once
    gc.collect()
    assert key not in tr._SAMPLERS


@pytest.mark.parametrize("others, name", [({"bogus": 1.0}, "bogus"), ({"frequency": 2.0, "radius": 0.1, "x": 0.0}, "radius")])
def test_a_parameter_the_trajectory_has_not_is_refused_naming_it_and_listing_its_parameters(others, name):
    """from_parameters with a name outside PARAMETERS (an FMU parameter misspelt in a scene):
    refused naming the first unknown one, its parameters listed in PARAMETERS' order
    (docs/contract.md: "refuses a name not in it by name")."""
    from controller.trajectories import PARAMETERS

    with pytest.raises(ValueError) as caught:
        from_parameters("circle", PRESET_CYCLES, **others)
    assert str(caught.value) == (f"parameter {name}: the Trajectory has no such parameter; its parameters: "
                                 f"{', '.join(PARAMETERS)}")
    assert {"side_time", "frequency", "x_hold", "y_hold"} <= set(PARAMETERS)     # the ones **others may name
