"""The controller's kinematics (the C kernel kinematics5r.c) against plant.fivebar and the general
algorithm's C, c."""
import numpy as np
import pytest

from controller.kinematics import Kinematics
from plant import fivebar, get_preset
from plant.parallel import inverse_dynamics_terms, mechanism_state

POINTS = [(0.0, 0.17), (0.07, 0.17), (-0.04, 0.12), (0.03, 0.25)]


@pytest.mark.parametrize("preset", ["bench", "thesis_sim"])
@pytest.mark.parametrize("x, y", POINTS)
def test_kinematics_match_the_plant(preset, x, y):
    """Catches controller kinematics (C) that differ from the plant's inverse, direct kinematics or margin."""
    params = get_preset(preset)
    kin, mech = Kinematics(params), fivebar.build_mechanism(params)
    ang = fivebar.inverse_kinematics(params, x, y)
    assert np.allclose(kin.inverse(x, y), ang, atol=1e-14)
    assert np.allclose(kin.forward(ang[0], ang[2]), (x, y), atol=1e-14)
    assert kin.margin(x, y) == pytest.approx(fivebar.singularity(params, x, y).margin, abs=1e-14)
    q7 = fivebar.thesis_coordinates(params, x, y)
    C = mechanism_state(mech, q7, np.zeros(7)).C
    dxy = np.array([0.3, -0.2])
    dq7 = C @ dxy
    q_thesis, dq_thesis = kin.thesis_state(x, y, *dxy)
    assert np.allclose(q_thesis, q7, atol=1e-14) and np.allclose(dq_thesis, dq7, atol=1e-13)
    # Joint accelerations at ddx# = 0 are the constraint bias c (5.69): task_state must give ddx = 0.
    c = inverse_dynamics_terms(mech, q7, dq7).c
    dq1, dq2 = fivebar.world_rates(dq7)
    ddq1, ddq2 = fivebar.world_rates(c)
    state = kin.task_state(ang[0], ang[2], dq1, dq2, ddq1, ddq2)
    assert np.allclose(state[2:4], dxy, atol=1e-13)
    assert np.allclose(state[4:6], 0.0, atol=1e-12)
    # joint_reference inverts task_state.
    ddx = (1.5, -0.7)
    ref = kin.joint_reference(x, y, *dxy, *ddx)
    back = kin.task_state(*ref)
    assert np.allclose(back[:6], (x, y, *dxy, *ddx), atol=1e-12)
