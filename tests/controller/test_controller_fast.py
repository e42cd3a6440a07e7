"""The controller's exact model by two formulations, and the law's refusals.

* :func:`plant.fast5r.inverse_terms` equals :func:`plant.parallel.inverse_dynamics_terms`
  (M_M, v_M, g_M, Z, c) at random states of both presets, with m0, gravity and rotors;
* :class:`ExactModel` with the compiled kernel equals the general one, and so does the exact
  controller;
* every refusal of the law's kernel becomes one message naming the variable, its value and
  the time, and leaves the law's state alone; off the table the exact model takes over.
"""
import math
import re
from dataclasses import replace

import numpy as np
import pytest

import kernels
from controller.model import ExactModel
from controller.position import PositionController
from controller.strategies import get_strategy
from plant import fast5r, fivebar, get_preset
from plant.parallel import inverse_dynamics_terms, mechanism_state
from tests.support.poses import random_poses

BENCH = get_preset("bench")
#: Reaches the near-singular band at the top and bottom: cells with left-out corners.
REGION = (-0.10, 0.10, 0.02, 0.28)
NAMES = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")


def loaded(preset):
    """The preset with an end-effector mass, in-plane gravity and rotors: every term non-zero."""
    return replace(get_preset(preset), m0=0.031, gravity=(1.3, -9.81, 0.0)).with_rotors(1.469e-4, 1.887e-4)


def rel_err(a, b):
    a, b = np.asarray(a, dtype=float).ravel(), np.asarray(b, dtype=float).ravel()
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


# --- the compiled inverse dynamics -----------------------------------------------------------
@pytest.mark.parametrize("preset", ["bench", "thesis_sim"])
def test_fast_inverse_terms_equal_the_general_algorithm(preset):
    """Catches a fast inverse-dynamics kernel term that differs from the general algorithm's."""
    params = loaded(preset)
    mech, p = fivebar.build_mechanism(params), fast5r.pack_params(params)
    rng = np.random.default_rng(7)
    out = np.empty(fast5r.INVERSE_SIZE)
    for x, y in random_poses(params, rng, 60):
        q = fivebar.thesis_coordinates(params, x, y)
        C = mechanism_state(mech, q, np.zeros(7)).C
        for dq in (C @ rng.normal(0.0, 1.0, 2), np.zeros(7)):
            ref = inverse_dynamics_terms(mech, q, dq)
            fast5r.inverse_terms(p, q, dq, out)
            assert rel_err(out[fast5r.INVERSE_M:fast5r.INVERSE_M + 4], ref.M) < 1e-10
            assert rel_err(out[fast5r.INVERSE_G:fast5r.INVERSE_G + 2], ref.g) < 1e-10
            assert rel_err(out[fast5r.INVERSE_Z:fast5r.INVERSE_Z + 4], ref.Z) < 1e-10
            if dq.any():
                assert rel_err(out[fast5r.INVERSE_V:fast5r.INVERSE_V + 2], ref.v) < 1e-10
                assert rel_err(out[fast5r.INVERSE_C:fast5r.INVERSE_C + 7], ref.c) < 1e-10
            else:
                assert not out[fast5r.INVERSE_V:fast5r.INVERSE_V + 2].any()


@pytest.mark.parametrize("preset", ["bench", "thesis_sim"])
def test_exact_model_kernels_agree(preset):
    """Catches an exact model whose fast (C) and general (Python) kernels give different terms."""
    params = loaded(preset)
    fast, general = ExactModel(params), ExactModel(params, kernel="general")
    rng = np.random.default_rng(3)
    for x, y in random_poses(params, rng, 30):
        dx, dy = rng.normal(0.0, 0.5, 2)
        a, b = fast.terms(x, y, dx, dy), general.terms(x, y, dx, dy)
        assert rel_err(a[:3], b[:3]) < 1e-10 and rel_err(a[3:], b[3:]) < 1e-10
        assert rel_err(fast.last_Z, general.last_Z) < 1e-10
        assert rel_err(fast.row(x, y), general.row(x, y)) < 1e-10
    with pytest.raises(ValueError, match="kernel = 'numpy' is unknown"):
        ExactModel(params, kernel="numpy")


def moving_samples(rng, n, poses):
    """Measurements near a pose and references a few mm away, velocities and accelerations
    large enough for |s| on both sides of phi."""
    samples = []
    for k in range(n):
        x, y = poses[k % len(poses)]
        ang = fivebar.inverse_kinematics(BENCH, x, y)
        meas = (ang[0] + rng.normal(0, 1e-3), ang[2] + rng.normal(0, 1e-3), *rng.normal(0, 1.0, 2),
                *rng.normal(0, 20.0, 2))
        ref = (x + rng.normal(0, 3e-3), y + rng.normal(0, 3e-3), *rng.normal(0, 0.3, 2), *rng.normal(0, 5.0, 2))
        samples.append(meas + ref)
    return samples


@pytest.mark.parametrize("space", ["q", "x"])
def test_exact_controller_kernels_agree(space):
    """Catches TC and TCMD controllers whose compiled and general kernels give different torques."""
    rng = np.random.default_rng(11)
    poses = random_poses(BENCH, rng, 20, band=0.2)
    for name in (f"TC{space}", f"TCMD{space}"):
        fast = PositionController(BENCH, get_strategy(name), model="exact", model_error=0.2)
        general = PositionController(BENCH, get_strategy(name), model="exact", model_error=0.2, kernel="general")
        assert fast.compiled and not general.compiled and fast.model.kernel == "fast" and general.model.kernel == "general"
        for k, values in enumerate(moving_samples(rng, 40, poses)):
            a, b = fast.step(k * 1e-3, *values), general.step(k * 1e-3, *values)
            assert rel_err(a, b) < 1e-10, (name, k, a, b)


def test_refusals_name_the_variable_and_leave_the_state_alone(tmp_path, monkeypatch):
    """Catches a compiled-law refusal that changes the state or names the wrong variable."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    ctrl = PositionController(BENCH, get_strategy("TCMDx"), grid_step=0.01, extent=REGION, table_fallback=False)
    assert ctrl.compiled
    x, y = 0.01, 0.15
    ang = fivebar.inverse_kinematics(BENCH, x, y)
    good = [ang[0], ang[2], 0.3, -0.2, 1.0, 0.5, x + 1e-3, y, 0.1, 0.2, -1.0, 0.5]
    ctrl.step(0.0, *good)
    top = fivebar.inverse_kinematics(BENCH, 0.0, 0.274)            # reachable, in a cell with a left-out corner
    side = fivebar.inverse_kinematics(BENCH, 0.115, 0.15)          # reachable, right of the region
    y_band = next(y for y in np.arange(0.0, 0.3, 0.001)
                  if 0.0 < fivebar.singularity(BENCH, 0.0, y).margin < fivebar.NEAR_SINGULAR_MARGIN)
    cases = [
        (dict(dq2=math.nan), "input dq2 = nan at t = 0.25 s is not finite"),
        (dict(x_d=0.5, y_d=0.1), "reference (x_d, y_d) = (0.5, 0.1) m at t = 0.25 s is outside the workspace"),
        (dict(x_d=0.0, y_d=y_band), "near-singular band"),
        (dict(q1=0.0, q2=math.pi), "measured (q1, q2) = (0.0, 3.14159"),
        (dict(q1=top[0], q2=top[2], x_d=0.0, y_d=0.27), "left out of the table"),
        (dict(q1=side[0], q2=side[2], x_d=0.1, y_d=0.15), "outside the tabulated region"),
        (dict(dq1=1e300), "at t = 0.25 s are not finite; largest input: dq1 = 1e+300"),   # the law overflows
    ]
    state = ctrl._buf.copy()
    for change, message in cases:
        values = dict(zip(NAMES, good), **change)
        with pytest.raises(kernels.Refused, match=re.escape(message)) as refused:
            ctrl.step(0.25, *values.values())
        assert refused.value.time == 0.25 and refused.value.record()["message"] == str(refused.value)
        assert np.array_equal(ctrl._buf, state)                 # nothing changed
    nan = pytest.raises(kernels.Refused, match="input dq2")
    with nan as refused:
        ctrl.step(0.25, *dict(zip(NAMES, good), dq2=math.nan).values())
    assert (refused.value.variable, refused.value.reason) == ("dq2", "NONFINITE")
    assert math.isnan(refused.value.value)


def test_unknown_kernel_is_refused():
    """Catches a controller accepting an unknown kernel name instead of refusing it."""
    with pytest.raises(ValueError, match="kernel = 'c' is unknown"):
        PositionController(BENCH, get_strategy("PDx"), kernel="c")


def test_step_with_errors_returns_the_errors():
    """Catches step_with_errors returning other torques than step, or stale errors."""
    ctrl = PositionController(BENCH, get_strategy("PDq"))
    x, y = 0.01, 0.15
    ang = fivebar.inverse_kinematics(BENCH, x, y)
    out = ctrl.step_with_errors(0.0, ang[0], ang[2], 0, 0, 0, 0, x + 1e-3, y, 0, 0, 0, 0)
    assert out[4:] == tuple(ctrl.e) and out[:4] == PositionController(BENCH, get_strategy("PDq")).step(
        0.0, ang[0], ang[2], 0, 0, 0, 0, x + 1e-3, y, 0, 0, 0, 0)


def test_table_fallback_uses_the_exact_model_off_the_table(tmp_path, monkeypatch):
    """Catches a table fallback that refuses, or differs from the exact model, off the table."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    strategy = get_strategy("TCx")
    tabulated = PositionController(BENCH, strategy, grid_step=0.01, extent=REGION)
    exact = PositionController(BENCH, strategy, model="exact")
    for x, y in ((0.0, 0.274), (0.115, 0.15)):   # a left-out cell corner; right of the region
        ang = fivebar.inverse_kinematics(BENCH, x, y)
        values = [ang[0], ang[2], 0.3, -0.2, 1.0, 0.5, x + 1e-3, y, 0.1, 0.2, -1.0, 0.5]
        got = tabulated.step(0.0, *values)
        want = exact.step(0.0, *values)
        assert np.allclose(got, want, rtol=1e-9, atol=1e-12)
    assert tabulated.fallbacks == 2
