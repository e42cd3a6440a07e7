"""``pc_5r_bias_rhs`` (kernels/src/kinematics5r.c), the exported velocity-quadratic part of the
differentiated loop constraint, dJ_X dx + dJ_Theta dq: differentiating J_X dx + J_Theta dq = 0
once more gives J_X ddx + J_Theta ddq + rhs = 0, so along a motion with ddq = 0 the rhs is
-J_X ddx, where ddx is found here by a central second difference of the forward kinematics
along q(t) = q + dq t.  No other test called this entry point (the task state computes the same
term internally)."""
from __future__ import annotations

import ctypes

import numpy as np
import pytest

import kernels
from plant import get_preset
from plant import kinematics5r as k5

_D = ctypes.POINTER(ctypes.c_double)
_bias_rhs = kernels.function("pc_5r_bias_rhs", None, ctypes.POINTER(k5.Geometry), *([ctypes.c_double] * 8), _D)


def forward(g, q1, q2):
    x, y, distance = ctypes.c_double(), ctypes.c_double(), ctypes.c_double()
    assert k5.forward(ctypes.byref(g), q1, q2, x, y, distance) == k5.OK
    return np.array([x.value, y.value])


def as_array(values):
    return np.ctypeslib.as_array(values)


@pytest.mark.parametrize("preset", ["bench", "thesis_sim"])
@pytest.mark.parametrize("point, dq", [((0.01, 0.15), (1.3, -0.8)), ((-0.04, 0.2), (-2.0, 0.5)),
                                       ((0.05, 0.12), (0.7, 1.9))])
def test_the_bias_is_minus_j_x_times_the_acceleration_of_a_motion_at_constant_joint_rates(preset, point, dq):
    """rhs = -J_X ddx with ddx = d^2/dt^2 of the forward kinematics at constant joint rates
    (h = 1e-4 s: the difference's error ~1e-8 relative), every rate and both coordinates
    non-zero so that each of the rhs' terms counts."""
    g = k5.geometry(get_preset(preset))
    angles = (ctypes.c_double * 4)()
    distance = ctypes.c_double()
    assert k5.inverse(ctypes.byref(g), point[0], point[1], angles, ctypes.byref(distance)) == k5.OK
    q1, q2 = angles[0], angles[2]
    dq1, dq2 = dq
    x, y = forward(g, q1, q2)
    h = 1e-4
    ahead, behind = forward(g, q1 + h * dq1, q2 + h * dq2), forward(g, q1 - h * dq1, q2 - h * dq2)
    ddx = (ahead - 2.0 * np.array([x, y]) + behind) / h ** 2
    jx, jt = (ctypes.c_double * 4)(), (ctypes.c_double * 2)()
    k5.jacobians(ctypes.byref(g), x, y, q1, q2, jx, jt)
    J_X = as_array(jx).reshape(2, 2)
    dx = np.linalg.solve(J_X, -as_array(jt) * np.array([dq1, dq2]))   # the constraint: J_X dx = -J_Theta dq
    rhs = (ctypes.c_double * 2)()
    _bias_rhs(ctypes.byref(g), x, y, q1, q2, dx[0], dx[1], dq1, dq2, rhs)
    expected = -J_X @ ddx
    np.testing.assert_allclose(as_array(rhs), expected, rtol=1e-6, atol=1e-6 * np.abs(expected).max())
    assert np.abs(expected).min() > 1e-4
