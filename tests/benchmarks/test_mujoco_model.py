"""The MuJoCo comparison model (benchmarks/mujoco_5r.py) against the Lagrange reference.

Mass properties and velocity terms must match the reference to round-off;
trajectories only to the accuracy MuJoCo's soft ``connect`` closure allows
(measured 3e-8 m to 3e-7 m over 0.4 s with RK4 at 1 ms; asserted at 1e-6 m).
"""

import mujoco  # in the test extra: a missing MuJoCo is a failure, not a skip
import numpy as np
import pytest

from benchmarks import mujoco_5r
from tests.support import lagrange5r as ref

pytestmark = [pytest.mark.tools]

#: Loose bound on the tip deviation caused by MuJoCo's soft closure [m].
SOFT_CLOSURE_TOLERANCE = 1e-6

#: Relative qpos (q1, elbow1, q2, elbow2) to absolute angles (phi11, phi12, phi21, phi22).
RELATIVE_TO_ABSOLUTE = np.array([[1.0, 0.0, 0.0, 0.0],
                                 [1.0, 1.0, 0.0, 0.0],
                                 [0.0, 0.0, 1.0, 0.0],
                                 [0.0, 0.0, 1.0, 1.0]])


def _bench_with_tip_mass_and_gravity():
    params = ref.params_bench()
    params["m0"] = 0.05
    params["g"] = (0.5, -0.8, -9.81)
    return params


def _model_and_data(params, **options):
    model = mujoco.MjModel.from_xml_string(mujoco_5r.mjcf_5r(params, **options))
    return model, mujoco.MjData(model)


def test_mjcf_settings():
    """Catches a MuJoCo model whose DOFs, step, integrator, contacts, gravity or armature differ from the bench."""
    params = ref.params_bench()
    model, _ = _model_and_data(params)
    assert (model.nq, model.nv, model.nu, model.neq) == (4, 4, 2, 1)
    assert model.opt.timestep == 1e-3
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    assert np.allclose(model.opt.gravity, 0.0)
    assert np.allclose(model.dof_armature, [1.469e-4, 0.0, 1.887e-4, 0.0])
    assert np.allclose(model.dof_damping, 0.0)
    assert list(model.actuator_trnid[:, 0]) == [model.joint("q1").id, model.joint("q2").id]
    assert np.allclose(model.actuator_gear[:, 0], 1.0)
    assert not model.actuator_ctrllimited.any()
    assert model.eq_type[0] == mujoco.mjtEq.mjEQ_CONNECT


def test_initial_state_closes_at_the_requested_tip():
    """Catches the MuJoCo model's initial joint angles not closing both chains at the requested tip."""
    params = ref.params_thesis_sim()
    model, data = _model_and_data(params)
    data.qpos[:] = mujoco_5r.mujoco_initial_state(params, 0.07, 0.17)
    mujoco.mj_forward(model, data)
    assert np.allclose(data.site("tip1").xpos, (0.07, 0.17, 0.0), atol=1e-15)
    assert np.allclose(data.site("tip2").xpos, (0.07, 0.17, 0.0), atol=1e-15)


def test_mass_matrix_and_bias_forces_match_reference():
    """Catches the MuJoCo 5R's mass matrix, bias forces or rotor armature differing from the reference
    model (mapped through the relative-to-absolute angles)."""
    params = _bench_with_tip_mass_and_gravity()
    model, data = _model_and_data(params)
    phi = np.array(ref.ik(params, -0.03, 0.19)) + [0.1, -0.2, 0.3, 0.05]  # any angles: open chains
    dphi = np.array([1.2, -0.8, 0.6, 2.0])
    data.qpos[:] = np.linalg.solve(RELATIVE_TO_ABSOLUTE, phi)
    data.qvel[:] = np.linalg.solve(RELATIVE_TO_ABSOLUTE, dphi)
    mujoco.mj_forward(model, data)
    mass = np.zeros((4, 4))
    mujoco.mj_fullM(model, data, mass)

    # phi = T qpos, so the reference's matrices map with T^T ... T; the rotor
    # inertia in the reference's link-11 term must reappear as MuJoCo's armature.
    jacobian = RELATIVE_TO_ABSOLUTE
    expected_mass = jacobian.T @ ref.mass_matrix(params, phi) @ jacobian
    assert np.allclose(mass, expected_mass, rtol=1e-12, atol=1e-16)
    expected_bias = jacobian.T @ (ref.velocity_forces(params, phi, dphi)
                                  - ref.gravity_forces(params, phi))
    assert np.allclose(data.qfrc_bias, expected_bias, rtol=1e-10, atol=1e-14)


def _constant_torques(t):
    return 0.03, -0.02


def _sinusoidal_torques(t):
    return 0.05 * np.sin(2 * np.pi * t) + 0.02, -0.03 * np.cos(3 * t)


@pytest.mark.parametrize("preset, x0, y0, tau_fn", [
    ("bench", 0.0, 0.17, _constant_torques),
    ("thesis_sim", 0.07, 0.17, lambda t: (-0.01, 0.008)),
])
def test_trajectory_with_constant_torques_matches_reference(preset, x0, y0, tau_fn):
    """Catches the MuJoCo model moving otherwise than the reference under constant torques beyond its soft
    closure's tolerance, or not moving."""
    params = {"bench": ref.params_bench, "thesis_sim": ref.params_thesis_sim}[preset]()
    t, x, y, gap = mujoco_5r.mujoco_trajectory(params, x0, y0, tau_fn, 0.4)
    _, x_ref, y_ref, _, _ = ref.simulate(params, x0, y0, tau_fn, 0.4, t_eval=t)
    assert np.hypot(x_ref[-1] - x0, y_ref[-1] - y0) > 0.03  # a real motion
    assert np.max(np.hypot(x - x_ref, y - y_ref)) < SOFT_CLOSURE_TOLERANCE
    assert np.max(gap) < SOFT_CLOSURE_TOLERANCE


def test_trajectory_with_held_torques_matches_reference():
    """Catches the MuJoCo run holding the torques over other intervals than the reference's zero-order
    hold."""
    params = ref.params_bench()
    t, x, y, _ = mujoco_5r.mujoco_trajectory(params, 0.0, 0.17, _sinusoidal_torques, 0.3)
    t_ref, x_ref, y_ref = mujoco_5r.reference_zoh_trajectory(params, 0.0, 0.17,
                                                             _sinusoidal_torques, 0.3)
    assert np.allclose(t, t_ref, atol=1e-12)
    assert np.max(np.hypot(x - x_ref, y - y_ref)) < SOFT_CLOSURE_TOLERANCE


def test_step_time_is_measured():
    """Catches a MuJoCo step timer that returns zero, a negative or an absurd time."""
    assert 0.0 < mujoco_5r.mujoco_step_time_us(ref.params_bench(), n_steps=200) < 1e4
