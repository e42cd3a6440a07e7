"""The Trajectory slave stepped at 2 ms from a start time of 0.25 s (0 by default), at 1.5 Hz
for 3 cycles (defaults 1 Hz, 8): its outputs after each step against the bench circle's closed
form (7.23) written here, and the triangle's vertices at the ends of its sides (issue 31:
a second sample time, parameters off their defaults)."""
from __future__ import annotations

import math

import pytest

from fmus.cosim.backends import InProcessInstance

H, T0 = 2e-3, 0.25
OUTPUTS = ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")


def _circle(t, f=1.5, cycles=3):
    """x = -r sin 2 pi f t, y = 0.158 - r cos 2 pi f t, r = 0.05, until cycles / f; then held
    at (0, 0.108) at rest."""
    if t > cycles / f:
        return (0.0, 0.108, 0.0, 0.0, 0.0, 0.0)
    w, r = 2 * math.pi * f, 0.05
    return (-r * math.sin(w * t), 0.158 - r * math.cos(w * t), -r * w * math.cos(w * t), r * w * math.sin(w * t),
            r * w * w * math.sin(w * t), r * w * w * math.cos(w * t))


def _run(parameters, steps):
    instance = InProcessInstance("Trajectory", "traj")
    instance.initialize(parameters, T0)
    rows = [[getattr(instance.slave, name) for name in OUTPUTS]]
    for k in range(steps):
        instance.do_step(T0 + k * H, H)
        rows.append([getattr(instance.slave, name) for name in OUTPUTS])
    return instance.slave, rows


def test_the_circle_at_2ms_from_a_later_start_is_the_closed_form_at_the_end_of_each_step():
    """Catches the outputs published at the step's start (t) instead of its end (t + h), the
    start time ignored (the first outputs at 0), the frequency or the cycles not passed."""
    slave, rows = _run({"kind": "circle", "frequency": 1.5, "cycles": 3}, steps=1000)   # to 2.25 s: past the stop
    for k, row in enumerate(rows):
        t = T0 + k * H
        if abs(t - 2.0) > 1e-9:            # the stop's own instant: the velocity jumps there
            assert row == pytest.approx(_circle(t), rel=1e-9, abs=1e-12), k
    assert (slave.x_start, slave.y_start) == (-0.002, 0.108)
    assert rows[-1] == pytest.approx([0.0, 0.108, 0.0, 0.0, 0.0, 0.0], abs=1e-15)   # the last point, at rest


def test_the_triangle_reaches_each_vertex_at_rest_at_the_end_of_its_side():
    """side_time 0.6 s (default 0.75), 1 cycle (default 2): at 0.6, 1.2 and 1.8 s after the start
    the vertices x_2, x_3, x_1 of (7.24-7.26) with zero velocity and acceleration, from t = 0.25 s
    at 2 ms steps (the trajectory's time is the master's: the start time is not subtracted)."""
    slave, rows = _run({"kind": "triangle", "side_time": 0.6, "cycles": 1}, steps=900)
    vertices = {0.6: (0.050, 0.258), 1.2: (-0.050, 0.258), 1.8: (-0.002, 0.108)}
    for t, (x, y) in vertices.items():
        row = rows[round((t - T0) / H)]
        assert row[:2] == pytest.approx([x, y], abs=1e-12) and row[2:] == pytest.approx([0.0] * 4, abs=1e-9), t
    assert rows[-1][:2] == pytest.approx([-0.002, 0.108], abs=1e-15)     # held at x_1 after the cycle
