"""``CircleTrajectory.buf`` read back word by word against ``pc_trajectory_circle``
(kernels/src/trajectory.h): the kind, the centre, radius, angles, duration, and ``stops``
as the header encodes it (1.0: hold the last point, 0.0: keep circling)."""
import math

import pytest

from controller import fasttrajectory as fast
from controller.trajectories import CircleTrajectory


@pytest.mark.parametrize("stops", [True, False])
def test_a_circles_buffer_holds_each_field_as_trajectory_h_encodes_it(stops):
    c = CircleTrajectory(center=(0.01, 0.158), radius=0.05, initial_angle=-math.pi / 2,
                         angular_velocity=-2 * math.pi, duration=8.0, stops=stops, start_point=(-0.002, 0.108))
    buf = c.buf
    assert buf.size == fast.T_STOPS + 1
    assert buf[fast.T_KIND] == fast.KIND_CIRCLE == 0.0
    assert (buf[fast.T_CX], buf[fast.T_CY], buf[fast.T_RADIUS]) == (0.01, 0.158, 0.05)
    assert (buf[fast.T_PHI0], buf[fast.T_OMEGA], buf[fast.T_DURATION]) == (-math.pi / 2, -2 * math.pi, 8.0)
    assert buf[fast.T_STOPS] == (1.0 if stops else 0.0)
