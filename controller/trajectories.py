"""Reference trajectories of the end effector with analytic derivatives (thesis 7.18, 7.23-7.28).

Every trajectory is an immutable object called with the time ``t`` >= 0 (s) and
returning a :class:`ReferenceSample` ``(x, y, dx, dy, ddx, ddy)`` in the world frame
(m, m/s, m/s^2). It also carries

* ``start_point``: where the mechanism starts at rest (7.17, 7.28, SYSTEM.md section 4);
  for ``circle`` it is not the reference's first point;
* ``duration``: the length of the reference's motion, s. ``circle`` and ``triangle``
  hold their last point (velocity and acceleration zero) from then on; a scene runs
  at least this long.

Kinds (:func:`get_trajectory`): ``thesis_circle``, ``circle``, ``triangle``, ``hold``.
Evaluation is scalar and uses ``math`` only (a few microseconds per call).
"""

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

BENCH_START = (-0.002, 0.108)
"""Vertex x_1 of the triangle and the bench's initial position at rest, m (7.24, 7.28)."""

SMOOTHSTEP_COEFFICIENTS = (0.0, 0.0, 0.0, 0.0, 35.0, -84.0, 70.0, -20.0)
"""s(tau) = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7 (7.27), ascending powers: s(0) = 0,
s(1) = 1, and s', s'', s''' vanish at both ends."""
_SMOOTHSTEP_DERIVATIVES = tuple(
    tuple(float(c) for c in np.polynomial.polynomial.polyder(SMOOTHSTEP_COEFFICIENTS, order)) for order in (1, 2)
)
"""Ascending coefficients of s'(tau) and s''(tau), differentiated from (7.27)."""


class ReferenceSample(NamedTuple):
    """Reference position, velocity and acceleration of the end effector at one instant."""

    x: float
    y: float
    dx: float
    dy: float
    ddx: float
    ddy: float


def _check_time(t):
    if not t >= 0.0:
        raise ValueError(f"trajectory time must be >= 0 s, got {t}")


def _polynomial(coefficients, tau):
    """Horner evaluation of a polynomial given in ascending powers."""
    value = 0.0
    for coefficient in reversed(coefficients):
        value = value * tau + coefficient
    return value


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

    def __call__(self, t):
        """Reference at time ``t`` (s), a :class:`ReferenceSample`."""
        _check_time(t)
        moving = not (self.stops and t >= self.duration)
        angle = self.initial_angle + self.angular_velocity * (t if moving else self.duration)
        cosine, sine = math.cos(angle), math.sin(angle)
        x = self.center[0] + self.radius * cosine
        y = self.center[1] + self.radius * sine
        if not moving:
            return ReferenceSample(x, y, 0.0, 0.0, 0.0, 0.0)
        speed = self.radius * self.angular_velocity
        centripetal = self.radius * self.angular_velocity**2
        return ReferenceSample(x, y, -speed * sine, speed * cosine, -centripetal * cosine, -centripetal * sine)


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
        Number of rounds.
    """

    vertices: tuple
    side_time: float
    cycles: int

    @property
    def start_point(self):
        """The first vertex, where the mechanism starts at rest."""
        return self.vertices[0]

    @property
    def duration(self):
        """Time to travel all sides ``cycles`` times, s."""
        return self.cycles * len(self.vertices) * self.side_time

    def __call__(self, t):
        """Reference at time ``t`` (s), a :class:`ReferenceSample`."""
        _check_time(t)
        if t >= self.duration:
            return ReferenceSample(*self.start_point, 0.0, 0.0, 0.0, 0.0)
        side = min(math.floor(t / self.side_time), self.cycles * len(self.vertices) - 1)
        tau = t / self.side_time - side
        x0, y0 = self.vertices[side % len(self.vertices)]
        x1, y1 = self.vertices[(side + 1) % len(self.vertices)]
        position = _polynomial(SMOOTHSTEP_COEFFICIENTS, tau)
        velocity = _polynomial(_SMOOTHSTEP_DERIVATIVES[0], tau) / self.side_time
        acceleration = _polynomial(_SMOOTHSTEP_DERIVATIVES[1], tau) / self.side_time**2
        dx, dy = x1 - x0, y1 - y0
        return ReferenceSample(
            x0 + dx * position, y0 + dy * position, dx * velocity, dy * velocity, dx * acceleration, dy * acceleration
        )


@dataclass(frozen=True)
class HoldTrajectory:
    """A constant reference at ``point`` (m), which is also the start point."""

    point: tuple
    duration: float = 0.0

    @property
    def start_point(self):
        """The held point."""
        return self.point

    def __call__(self, t):
        """Reference at time ``t`` (s): the held point at rest."""
        _check_time(t)
        return ReferenceSample(*self.point, 0.0, 0.0, 0.0, 0.0)


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
