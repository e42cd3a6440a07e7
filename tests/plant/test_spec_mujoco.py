"""The spatial Delta-like spec (plant/specs/delta3.toml) against MuJoCo: a model generated
from the same spec (benchmarks/mujoco_spec.py), Newton-Euler dynamics with the loop
closures as equality constraints, shares no formulation with plant/."""

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
from benchmarks import mujoco_spec  # noqa: E402
from plant import spec as plant_spec  # noqa: E402
from plant.parallel import mechanism_state  # noqa: E402
from plant.specsim import assemble  # noqa: E402

pytestmark = [pytest.mark.slow, pytest.mark.tools]


@pytest.mark.parametrize("name", ["delta3", "bench_5r", "balanced_5r"])
def test_mass_matrix_and_bias_forces_equal_mujoco(name):
    """Catches a spec mechanism's mass matrix or bias forces differing from MuJoCo's for the same MJCF (a
    frame, inertia or closure wrong in either)."""
    spec = plant_spec.load(name)
    q = assemble(spec, spec.start)
    rng = np.random.default_rng(5)
    C = mechanism_state(spec.mechanism, q, np.zeros_like(q)).C
    dq = C @ rng.normal(size=C.shape[1])
    model = mujoco.MjModel.from_xml_string(mujoco_spec.mjcf_from_spec(spec))
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = q, dq
    mujoco.mj_forward(model, data)
    M = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    st = mechanism_state(spec.mechanism, q, dq)
    # MuJoCo's massless bodies carry mujoco_spec.MIN_INERTIAL (1e-12)
    assert np.max(np.abs(M - st.M)) < 1e-10
    assert np.max(np.abs(data.qfrc_bias - (st.v + st.g))) < 1e-10
    for i in range(len(spec.chains)):
        assert np.allclose(data.site(f"tip{i}").xpos, data.site(f"attach{i}").xpos, atol=1e-13)


def test_delta_moves_as_mujoco_over_one_second():
    """Catches the delta robot moving otherwise than in MuJoCo over 1 s under the same torques beyond 1 µm,
    or not moving."""
    spec = plant_spec.load("delta3")
    q0 = assemble(spec, spec.start)
    fn = mujoco_spec.delta_torques(mujoco_spec.holding_torques(spec, q0))
    _, ours = mujoco_spec.spec_run(spec, fn, 1.0)
    theirs = mujoco_spec.mujoco_run(spec, q0, fn, 1.0)
    assert np.linalg.norm(ours - ours[0], axis=1).max() > 0.03          # a real motion
    assert np.max(np.linalg.norm(ours - theirs, axis=1)) <= 1e-6
