"""Reference trajectories of the end effector with analytic derivatives (thesis 7.18, 7.23-7.28).

Every trajectory is an immutable object called with the time ``t`` >= 0 (s) and
returning a :class:`ReferenceSample` ``(x, y, dx, dy, ddx, ddy)`` in the world frame
(m, m/s, m/s^2). It also carries

* ``start_point``: where the mechanism starts at rest (7.17, 7.28, the brief ../shared/spec/SYSTEM.md section 4);
  for ``circle`` it is not the reference's first point;
* ``duration``: the length of the reference's motion, s. ``circle`` and ``triangle``
  hold their last point (velocity and acceleration zero) from then on; a scene runs
  at least this long.

Kinds (:func:`get_trajectory`): ``thesis_circle``, ``circle``, ``triangle``, ``hold``.
Evaluation is one call of the C kernel ``pc_trajectory_sample`` (``kernels/src/trajectory.c``)
on the array each trajectory packs itself into (``buf``).
"""

import ctypes
import math
import weakref
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

import kernels

from . import fasttrajectory as _fast

BENCH_START = (-0.002, 0.108)
"""Vertex x_1 of the triangle and the bench's initial position at rest, m (7.24, 7.28)."""

SMOOTHSTEP_COEFFICIENTS = (0.0, 0.0, 0.0, 0.0, 35.0, -84.0, 70.0, -20.0)
"""s(tau) = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7 (7.27), ascending powers: s(0) = 0,
s(1) = 1, and s', s'', s''' vanish at both ends."""
_SMOOTHSTEP_DERIVATIVES = tuple(
    tuple(float(c) for c in np.polynomial.polynomial.polyder(SMOOTHSTEP_COEFFICIENTS, order)) for order in (1, 2)
)
"""Ascending coefficients of s'(tau) and s''(tau), differentiated from (7.27)."""
#: The coefficients of s'(tau), ascending (:mod:`controller.fastbalance` evaluates them too).
SMOOTHSTEP_SLOPE_COEFFICIENTS = _SMOOTHSTEP_DERIVATIVES[0]


class ReferenceSample(NamedTuple):
    """Reference position, velocity and acceleration of the end effector at one instant."""

    x: float
    y: float
    dx: float
    dy: float
    ddx: float
    ddy: float


_SAMPLE = kernels.function("pc_trajectory_sample", ctypes.c_int, ctypes.c_void_p, ctypes.c_long, ctypes.c_double,
                           ctypes.POINTER(ctypes.c_double), ctypes.POINTER(kernels.Refusal))
_SAMPLE_VALUES = ctypes.c_double * len(ReferenceSample._fields)
_REASONS = {
    _fast.BAD_TIME: kernels.Reason("bad_time", ("t",), "s", "trajectory time must be >= 0 s, got {value}"),
    _fast.BAD_LAYOUT: kernels.Reason("bad_layout", (), "",
                                     "the trajectory's buffer is damaged: word {index} = {value!r} does not fit it"),
}


#: id(trajectory) -> (its buffer, the values array, the refusal, sample(t) on them: :func:`kernels.bind`),
#: while the trajectory lives: kept out of the frozen trajectory, whose fields are its FMU
#: state and configuration.
_SAMPLERS = {}


def _sampler(trajectory, buf, values, refusal):
    """``pc_trajectory_sample`` of ``buf`` into ``values`` with ``refusal``: a call of t."""
    known = _SAMPLERS.get(id(trajectory))
    if known is not None and known[0] is buf and known[1] is values and known[2] is refusal:
        return known[3]
    if known is None:
        weakref.finalize(trajectory, _SAMPLERS.pop, id(trajectory), None)
    sample = kernels.bind(_SAMPLE, buf, buf.size, kernels.PER_CALL, values, refusal)
    _SAMPLERS[id(trajectory)] = (buf, values, refusal, sample)
    return sample


class _Context(ctypes.Structure):
    """``pc_trajectory_context``."""

    _fields_ = [("trajectory", ctypes.c_void_p), ("words", ctypes.c_long)]


def kernel_context(trajectory) -> _Context:
    """The ``pc_trajectory_context`` of ``trajectory``'s buffer, for ``pc_trajectory_io`` in
    the compiled loop; the caller keeps it alive (it keeps the buffer)."""
    buf = trajectory.buf
    context = _Context(kernels.address(buf), buf.size)
    context.keep = buf
    return context


def _evaluate(trajectory, t):
    """The :class:`ReferenceSample` of ``trajectory`` at ``t`` (s)."""
    return ReferenceSample(*sample_values(trajectory, t, *sample_buffers()))


def sample_buffers():
    """A values array and a refusal record for :func:`sample_values`, made once by a caller
    that samples every step (an FMU's doStep)."""
    return _SAMPLE_VALUES(), kernels.Refusal()


def sample_values(trajectory, t, values, refusal) -> list:
    """The reference of ``trajectory`` at ``t`` (s) as a list of floats in the order of
    :class:`ReferenceSample`'s fields, computed into ``values`` with ``refusal``
    (:func:`sample_buffers`): no object built per sample.

    Raises
    ------
    kernels.Refused
        (a ValueError) ``t`` below 0 or a damaged buffer, as :meth:`CircleTrajectory.__call__`.
    """
    if _sampler(trajectory, trajectory.buf, values, refusal)(t) != _fast.OK:
        raise kernels.refused(_REASONS, refusal, time=float(t), index=refusal.index)
    return values[:]


@dataclass(frozen=True)
class CircleTrajectory:
    """Uniform motion on a circle: x = cx + r cos(phi), y = cy + r sin(phi), phi = phi0 + w t.

    Parameters
    ----------
    center : tuple of float
        (cx, cy), m.
    radius : float
        r, m.
    initial_angle : float
        phi0, rad.
    angular_velocity : float
        w, rad/s (negative: clockwise).
    duration : float
        Length of the motion, s.
    stops : bool
        If true, the reference holds the point reached at ``duration`` afterwards
        (a sudden stop: position continuous, velocity and acceleration drop to zero);
        otherwise it keeps circling.
    start_point : tuple of float
        Initial position of the mechanism at rest, m.
    """

    center: tuple
    radius: float
    initial_angle: float
    angular_velocity: float
    duration: float
    stops: bool
    start_point: tuple

    @cached_property
    def buf(self):
        """This trajectory packed for ``pc_trajectory_sample``."""
        buf = np.zeros(_fast.T_STOPS + 1)
        buf[_fast.T_KIND] = _fast.KIND_CIRCLE
        buf[_fast.T_CX:_fast.T_CY + 1] = self.center
        buf[_fast.T_RADIUS], buf[_fast.T_PHI0], buf[_fast.T_OMEGA] = self.radius, self.initial_angle, self.angular_velocity
        buf[_fast.T_DURATION], buf[_fast.T_STOPS] = self.duration, 1.0 if self.stops else 0.0
        return buf

    def __call__(self, t):
        """Reference at time ``t`` (s), a :class:`ReferenceSample`."""
        return _evaluate(self, t)


@dataclass(frozen=True)
class PolygonTrajectory:
    """Closed polygon, each side travelled by the 7th-order polynomial (7.27) in ``side_time``.

    On side i, from vertex p_i to p_(i+1), with tau = (t - i side_time)/side_time in [0, 1):
    p = p_i + (p_(i+1) - p_i) s(tau), dp = (p_(i+1) - p_i) s'(tau)/side_time,
    ddp = (p_(i+1) - p_i) s''(tau)/side_time^2. After ``cycles`` rounds it holds the first vertex.

    Parameters
    ----------
    vertices : tuple of tuple of float
        Vertices in travel order, m; the last side closes back to the first.
    side_time : float
        Time per side, s.
    cycles : int
        Number of rounds, 1 to :data:`controller.fasttrajectory.MAX_CYCLES`.

    Raises
    ------
    ValueError
        ``cycles`` out of that range, naming it and its value.
    """

    vertices: tuple
    side_time: float
    cycles: int

    def __post_init__(self):
        if not 1 <= self.cycles <= _fast.MAX_CYCLES:
            raise ValueError(f"cycles = {self.cycles!r} must be between 1 and {_fast.MAX_CYCLES} (rounds of the polygon)")

    @property
    def start_point(self):
        """The first vertex, where the mechanism starts at rest."""
        return self.vertices[0]

    @property
    def duration(self):
        """Time to travel all sides ``cycles`` times, s."""
        return self.cycles * len(self.vertices) * self.side_time

    @cached_property
    def buf(self):
        """This trajectory packed for ``pc_trajectory_sample``."""
        points = np.asarray(self.vertices, dtype=float).ravel()
        buf = np.zeros(_fast.T_POINTS + points.size)
        buf[_fast.T_KIND] = _fast.KIND_POLYGON
        buf[_fast.T_SIDE_TIME], buf[_fast.T_CYCLES], buf[_fast.T_VERTICES] = self.side_time, self.cycles, len(self.vertices)
        buf[_fast.T_POSITION:_fast.T_VELOCITY] = SMOOTHSTEP_COEFFICIENTS
        buf[_fast.T_VELOCITY:_fast.T_ACCELERATION] = SMOOTHSTEP_SLOPE_COEFFICIENTS
        buf[_fast.T_ACCELERATION:_fast.T_POINTS] = _SMOOTHSTEP_DERIVATIVES[1]
        buf[_fast.T_POINTS:] = points
        return buf

    def __call__(self, t):
        """Reference at time ``t`` (s), a :class:`ReferenceSample`."""
        return _evaluate(self, t)


@dataclass(frozen=True)
class HoldTrajectory:
    """A constant reference at ``point`` (m), which is also the start point."""

    point: tuple
    duration: float = 0.0

    @property
    def start_point(self):
        """The held point."""
        return self.point

    @cached_property
    def buf(self):
        """This trajectory packed for ``pc_trajectory_sample``."""
        buf = np.zeros(_fast.T_HOLD_Y + 1)
        buf[_fast.T_KIND] = _fast.KIND_HOLD
        buf[_fast.T_HOLD_X:_fast.T_HOLD_Y + 1] = self.point
        return buf

    def __call__(self, t):
        """Reference at time ``t`` (s): the held point at rest."""
        return _evaluate(self, t)


def thesis_circle(cycles=2):
    """Circle of the simulation scene (7.18): x = 0.07 cos 2 pi t, y = 0.17 + 0.07 sin 2 pi t.

    The mechanism starts at rest at (0.07, 0.17) (7.17), on the circle but with the
    reference already moving at 0.44 m/s. The thesis gives no stop and no length:
    the reference circles for ever, ``cycles`` (default 2) only sets ``duration``.
    """
    return CircleTrajectory(
        center=(0.0, 0.17),
        radius=0.07,
        initial_angle=0.0,
        angular_velocity=2 * math.pi,
        duration=float(cycles),
        stops=False,
        start_point=(0.07, 0.17),
    )


def circle(cycles=8, frequency=1.0):
    """Bench circle (7.23): x = -0.05 sin 2 pi t, y = 0.158 - 0.05 cos 2 pi t, then a sudden stop.

    That is phi = -pi/2 - 2 pi t (clockwise) around (0, 0.158). After ``cycles`` periods
    of 1 s (8 in the thesis) the reference holds the last point (0, 0.108). The
    mechanism starts at rest at x_1 = (-0.002, 0.108) (7.28), 2 mm from the
    reference's first point.  ``frequency`` [Hz] (the thesis: 1) runs the same circle
    faster or slower: phi = -pi/2 - 2 pi frequency t, ``cycles`` periods of 1/frequency s.
    """
    if not (math.isfinite(frequency) and frequency > 0.0):
        raise ValueError(f"frequency = {frequency!r} Hz must be > 0")
    return CircleTrajectory(
        center=(0.0, 0.158),
        radius=0.05,
        initial_angle=-math.pi / 2,
        angular_velocity=-2 * math.pi * frequency,
        duration=float(cycles) / frequency,
        stops=True,
        start_point=BENCH_START,
    )


def triangle(side_time=0.75, cycles=2):
    """Bench triangle (7.24-7.27): x_1 -> x_2 -> x_3 -> x_1, ``side_time`` per side, then hold x_1.

    Vertices x_1 = (-0.002, 0.108) (7.24), x_2 = (0.050, 0.258) (7.25),
    x_3 = (-0.050, 0.258) (7.26); each side by the polynomial (7.27), with zero
    velocity, acceleration and jerk at the vertices; 2 cycles of 0.75 s sides in the
    thesis (4.5 s). The mechanism starts at rest at x_1 (7.28).
    """
    return PolygonTrajectory(vertices=(BENCH_START, (0.050, 0.258), (-0.050, 0.258)), side_time=side_time, cycles=cycles)


def hold(x=BENCH_START[0], y=BENCH_START[1]):
    """Hold the point (x, y), m; by default the bench's start x_1 (7.28)."""
    return HoldTrajectory(point=(float(x), float(y)))


TRAJECTORY_KINDS = {"thesis_circle": thesis_circle, "circle": circle, "triangle": triangle, "hold": hold}


def get_trajectory(kind, **params):
    """The trajectory named ``kind``, built with ``params``.

    Parameters
    ----------
    kind : str
        One of ``TRAJECTORY_KINDS``: "thesis_circle", "circle", "triangle", "hold".
    **params
        Keyword arguments of the matching constructor (:func:`thesis_circle`,
        :func:`circle`, :func:`triangle`, :func:`hold`).

    Raises
    ------
    ValueError
        If ``kind`` is unknown; the message lists the valid kinds.
    """
    try:
        constructor = TRAJECTORY_KINDS[kind]
    except (KeyError, TypeError):
        raise ValueError(f"unknown trajectory kind {kind!r}; valid kinds: {', '.join(TRAJECTORY_KINDS)}") from None
    return constructor(**params)


#: ``cycles`` meaning "the kind's default" in :func:`from_parameters` (thesis_circle 2, circle 8,
#: triangle 2): the Trajectory FMU's start value.
PRESET_CYCLES = -1


#: The Trajectory FMU's parameters and their start values: all a scene's ``Trajectory`` component
#: may set (:func:`from_parameters` takes the rest from here; the slave declares these; the real
#: ones are checked in this order).
PARAMETERS = {"kind": "circle", "cycles": PRESET_CYCLES, "side_time": 0.75, "x_hold": BENCH_START[0],
              "y_hold": BENCH_START[1], "frequency": 1.0}


def parameters_of(owner) -> dict:
    """The :data:`PARAMETERS` as ``owner`` (a Trajectory slave) holds them, by name."""
    return {name: getattr(owner, name) for name in PARAMETERS}


def from_parameters(kind=PARAMETERS["kind"], cycles=PRESET_CYCLES, **others):
    """The trajectory of the Trajectory FMU's parameters (a scene's ``Trajectory`` component, the
    slave's values, the native FMU's build): the one place they become a trajectory.

    Parameters
    ----------
    kind : str
        As :func:`get_trajectory`.
    cycles : int
        Rounds of circle and triangle; :data:`PRESET_CYCLES` for the kind's default.
    **others
        ``side_time`` (triangle: time per side [s]), ``frequency`` (circle: turns per second
        [Hz]), ``x_hold``, ``y_hold`` (hold: the point [m]); those not given: :data:`PARAMETERS`.

    Raises
    ------
    ValueError
        Naming the parameter and its value: ``cycles`` < 1 (not the preset), a ``side_time`` or
        ``frequency`` <= 0 where the kind uses it, an unknown ``kind``, a name the Trajectory
        does not have.
    """
    unknown = [name for name in others if name not in PARAMETERS]
    if unknown:
        raise ValueError(f"parameter {unknown[0]}: the Trajectory has no such parameter; its parameters: "
                         f"{', '.join(PARAMETERS)}")
    values = {**PARAMETERS, **others}
    side_time, frequency, x_hold, y_hold = (values[n] for n in ("side_time", "frequency", "x_hold", "y_hold"))
    if kind == "hold":
        kwargs = {"x": x_hold, "y": y_hold}
    else:
        kwargs = {}
        if cycles != PRESET_CYCLES:
            if cycles < 1:
                raise ValueError(f"parameter cycles = {cycles!r} must be >= 1 (or -1 for the default)")
            if kind == "triangle" and cycles > _fast.MAX_CYCLES:
                raise ValueError(f"parameter cycles = {cycles!r} must be <= {_fast.MAX_CYCLES} (rounds of the triangle)")
            kwargs["cycles"] = cycles
        if kind == "circle" and frequency != 1.0:
            if not frequency > 0.0:
                raise ValueError(f"parameter frequency = {frequency!r} Hz must be > 0")
            kwargs["frequency"] = frequency
        if kind == "triangle":
            if not side_time > 0.0:
                raise ValueError(f"parameter side_time = {side_time!r} s must be > 0")
            kwargs["side_time"] = side_time
    try:
        return get_trajectory(kind, **kwargs)
    except ValueError as exc:
        raise ValueError(f"parameter kind: {exc}") from None
