"""The reference trajectories' buffers (thesis 7.18, 7.23-7.27): their layout, read from the C
kernel.

The evaluation is the C kernel ``pc_trajectory_sample`` (``kernels/src/trajectory.c``), which
:mod:`controller.trajectories`, the Trajectory FMU slave and the compiled scene loop
(``pc_trajectory_io``) call on the array each trajectory packs itself into: the struct of its
kind (``pc_trajectory_circle``, ``_polygon``, ``_hold`` in ``kernels/src/trajectory.h``), whose
offsets come from the exported field lists.
"""
from __future__ import annotations

import ctypes

import kernels

OK = 0
#: t < 0 or not a number.
BAD_TIME = 1
#: An unknown kind, or sizes that do not fit the buffer.
BAD_LAYOUT = 2

KIND_CIRCLE, KIND_POLYGON, KIND_HOLD = 0.0, 1.0, 2.0
#: The most rounds of a polygon the kernel takes (``PC_TRAJECTORY_MAX_CYCLES``).
MAX_CYCLES = ctypes.c_int.in_dll(kernels.library(), "pc_trajectory_max_cycles").value
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
