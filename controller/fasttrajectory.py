"""The reference trajectories' buffers (thesis 7.18, 7.23-7.27): their layout, read from the C
kernel.

The evaluation is the C kernel ``pc_trajectory_sample`` (``kernels/src/trajectory.c``), which
:mod:`controller.trajectories`, the Trajectory FMU slave and the compiled scene loop call on
the array each trajectory packs itself into: the struct of its kind (``pc_trajectory_circle``,
``_polygon``, ``_hold`` in ``kernels/src/trajectory.h``), whose offsets come from the exported
field lists.

:func:`trajectory_io` is the compiled loop's numba call (:mod:`fmus.compiled`) until that loop
calls the C functions (``pc_trajectory_io``); its expressions are the kernel's, in the same
order (the same bits: ``tests/test_kernels_small.py``).
"""
from __future__ import annotations

import math

from numba import njit

import kernels

OK = 0
#: t < 0 or not a number.
BAD_TIME = 1
#: An unknown kind, or sizes that do not fit the buffer.
BAD_LAYOUT = 2

KIND_CIRCLE, KIND_POLYGON, KIND_HOLD = 0.0, 1.0, 2.0
CIRCLE = kernels.layout("pc_trajectory_circle_fields")
POLYGON = kernels.layout("pc_trajectory_polygon_fields")
HOLD = kernels.layout("pc_trajectory_hold_fields")
T_KIND = CIRCLE["kind"].start
#: Circle: centre, radius, initial angle, angular velocity, duration, stops (1.0 or 0.0).
T_CX, T_CY, T_RADIUS, T_PHI0, T_OMEGA, T_DURATION, T_STOPS = (
    CIRCLE[name].start for name in ("cx", "cy", "radius", "phi0", "omega", "duration", "stops"))
#: Polygon: time per side, cycles, vertices n, then the position, velocity, acceleration
#: polynomials of (7.27) in ascending powers (8, 7, 6 coefficients), then the n vertices (x, y).
T_SIDE_TIME, T_CYCLES, T_VERTICES, T_POSITION, T_VELOCITY, T_ACCELERATION, T_POINTS = (
    POLYGON[name].start for name in ("side_time", "cycles", "vertices", "position", "velocity", "acceleration",
                                     "points"))
#: Hold: the point.
T_HOLD_X, T_HOLD_Y = HOLD["x"].start, HOLD["y"].start


@njit(cache=True)
def _polynomial(buf, first, count, tau):  # pragma: no cover - numba
    """Horner evaluation of buf[first:first + count], ascending powers."""
    value = 0.0
    for k in range(count - 1, -1, -1):
        value = value * tau + buf[first + k]
    return value


@njit(cache=True)
def sample(buf, t):  # pragma: no cover - numba; goes with fmus/compiled.py's numba loop
    """(status, x, y, dx, dy, ddx, ddy): the reference at time t [s], as ``pc_trajectory_sample``."""
    if not t >= 0.0:
        return BAD_TIME, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    kind = buf[T_KIND]
    if kind == KIND_HOLD:
        return OK, buf[T_HOLD_X], buf[T_HOLD_Y], 0.0, 0.0, 0.0, 0.0
    if kind == KIND_CIRCLE:
        moving = not (buf[T_STOPS] != 0.0 and t >= buf[T_DURATION])
        w = buf[T_OMEGA]
        angle = buf[T_PHI0] + w * (t if moving else buf[T_DURATION])
        cosine, sine = math.cos(angle), math.sin(angle)
        r = buf[T_RADIUS]
        x = buf[T_CX] + r * cosine
        y = buf[T_CY] + r * sine
        if not moving:
            return OK, x, y, 0.0, 0.0, 0.0, 0.0
        speed = r * w
        centripetal = r * (w * w)
        return OK, x, y, -speed * sine, speed * cosine, -centripetal * cosine, -centripetal * sine
    n = int(buf[T_VERTICES])
    side_time = buf[T_SIDE_TIME]
    sides = int(buf[T_CYCLES]) * n
    if t >= sides * side_time:
        return OK, buf[T_POINTS], buf[T_POINTS + 1], 0.0, 0.0, 0.0, 0.0
    side = min(int(math.floor(t / side_time)), sides - 1)
    tau = t / side_time - side
    i0 = T_POINTS + 2 * (side % n)
    i1 = T_POINTS + 2 * ((side + 1) % n)
    x0, y0 = buf[i0], buf[i0 + 1]
    position = _polynomial(buf, T_POSITION, 8, tau)
    velocity = _polynomial(buf, T_VELOCITY, 7, tau) / side_time
    acceleration = _polynomial(buf, T_ACCELERATION, 6, tau) / (side_time * side_time)
    dx, dy = buf[i1] - x0, buf[i1 + 1] - y0
    return (OK, x0 + dx * position, y0 + dy * position, dx * velocity, dy * velocity,
            dx * acceleration, dy * acceleration)


@njit(cache=True)
def trajectory_io(buf, x, t, h):
    """Trajectory: x = [x_d, y_d, dx_d, dy_d, ddx_d, ddy_d], the reference at t + h."""
    status, a, b, c, d, e, f = sample(buf, t + h)
    if status == OK:
        x[0], x[1], x[2], x[3], x[4], x[5] = a, b, c, d, e, f
    return status
