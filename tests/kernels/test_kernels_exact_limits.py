"""C kernels hit exactly at the limits they accept (kernels/src/wheeled.c, kinematics5r.c): the
largest and smallest substep counts, an encoder count just above zero, a chain stretched
exactly straight, a joint reference with a proximal link along the tip's line.  On the limit
the kernel takes the documented branch; one past it, it refuses by the documented code and
index.  Values chosen exact in floating point (powers of two)."""
from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest

import kernels
from plant import kinematics5r as k5r
from plant import wheeled_kernel as K
from plant.wheeled import WheeledPendulum


def _io_step(substeps, count=1e-3):
    """One pc_wheeled_step_io of 1 ms from a tilted pendulum: (code, refusal, state after)."""
    sim = WheeledPendulum(initial=dict(psi=0.05))
    settings = np.zeros(K.SETTINGS_SIZE)
    settings[K.S_SUBSTEPS], settings[K.S_COUNT], settings[K.S_LIMIT] = substeps, count, 1e6
    x = np.zeros(3 + len(K.OUTPUT_NAMES))
    refusal = kernels.Refusal()
    code = K.step_io(sim.prm, sim.y, settings, x, 0.0, 1e-3, refusal)
    return code, refusal, sim.y.copy()


def test_the_most_substeps_is_the_documented_ten_thousand():
    """wheeled.h documents substeps as an integer in [1, 10000]; the Python layer reads the
    limit from the library."""
    assert K.MAX_SUBSTEPS == 10000


@pytest.mark.parametrize("substeps", [1.0, float(K.MAX_SUBSTEPS)])
def test_the_io_step_accepts_substeps_exactly_at_either_end_of_the_range(substeps):
    """Catches ``<`` for ``<=`` (or ``>`` for ``>=``) in the substep check of
    pc_wheeled_step_io: 1 and MAX_SUBSTEPS are accepted and the pendulum moves; one past
    either end is refused with index 0 (substeps) and the count as value, nothing changed."""
    start = WheeledPendulum(initial=dict(psi=0.05)).y.copy()
    code, _, after = _io_step(substeps)
    assert code == K.OK and not np.array_equal(after, start)
    past = substeps - 1.0 if substeps == 1.0 else substeps + 1.0
    code, refusal, after = _io_step(past)
    assert (code, refusal.index, refusal.value) == (K.BAD_SETTING, 0, past)
    np.testing.assert_array_equal(after, start)


def test_the_io_step_at_the_most_substeps_is_that_many_rk4_substeps():
    """The I/O step with MAX_SUBSTEPS takes the same RK4 substeps as pc_wheeled_step called
    with that count (same state bit for bit): the count is passed on, not clipped."""
    _, _, io = _io_step(float(K.MAX_SUBSTEPS))
    sim = WheeledPendulum(initial=dict(psi=0.05))
    assert K.calls(sim).step(0.0, 0.0, 0.0, 1e-3, K.MAX_SUBSTEPS) == K.OK
    np.testing.assert_array_equal(sim.y, io)


@pytest.mark.parametrize("substeps, code", [(0, K.BAD_SETTING), (1, K.OK), (K.MAX_SUBSTEPS, K.OK),
                                            (K.MAX_SUBSTEPS + 1, K.BAD_SETTING)])
def test_the_plain_step_accepts_exactly_one_to_the_most_substeps(substeps, code):
    """pc_wheeled_step's own check, the same range [1, MAX_SUBSTEPS] with both ends included."""
    sim = WheeledPendulum(initial=dict(psi=0.05))
    calls = K.calls(sim)
    assert calls.step(0.0, 0.0, 0.0, 1e-3, substeps) == code
    if code != K.OK:
        assert (calls.refusal.index, calls.refusal.value) == (0, substeps)


@pytest.mark.parametrize("count, code", [(2.0 ** -1074, K.OK), (0.0, K.BAD_SETTING), (-2.0 ** -1074, K.BAD_SETTING),
                                         (math.inf, K.BAD_SETTING)])
def test_the_io_step_takes_any_finite_positive_encoder_count(count, code):
    """The encoder count must be > 0 and finite: the smallest positive double is accepted,
    zero, the largest negative and infinity refused with index 1 (count)."""
    got, refusal, _ = _io_step(2.0, count)
    assert got == code
    if code != K.OK:
        assert (refusal.index, refusal.value) == (1, count)


def test_a_stretched_second_chain_is_singular_not_a_division_by_zero():
    """l0 = l11 = l12 = l21 = l22 = 1/4, q1 = q2 = 0: the elbows (1/2, 0) and (0, 0) are exactly
    l12 + l22 apart, the tip (1/4, 0) on the line of both elbows, so the Jacobian J_X has the
    rows (-1/4, 0) and (1/4, 0): det = 0 exactly.  pc_5r_task_state assembles the tip and
    reports SINGULAR with det 0 (not NO_ASSEMBLY, nor a velocity through 1 / 0)."""
    g = k5r.Geometry(0.25, 0.25, 0.25, 0.25, 0.25)
    task = k5r.Task()
    code = k5r.task_state(ctypes.byref(g), 0.0, 0.0, 0.5, -0.25, 0.0, 0.0, ctypes.byref(task))
    assert code == k5r.SINGULAR
    assert (task.x, task.y) == (0.25, 0.0)
    assert list(task.jx) == [-0.25, 0.0, 0.25, 0.0] and task.det == 0.0


@pytest.mark.parametrize("p11, p21, code", [(0.0, 0.5, k5r.SINGULAR), (0.5, 0.0, k5r.SINGULAR),
                                            (0.0, 0.0, k5r.SINGULAR), (0.5, 0.5, k5r.OK)])
def test_a_joint_reference_with_either_chain_along_its_proximal_link_is_singular(p11, p21, code):
    """pc_5r_joint_reference divides by J_Theta's entries l_k1 ((x -+ l0) sin p_k1 - y cos p_k1):
    the tip (1/2, 0) on the x axis with p_k1 = 0 makes chain k's entry exactly 0, so either chain
    alone (or both) gives SINGULAR; both proximal angles at 0.5 rad give finite joint rates and
    the angles passed back unchanged."""
    g = k5r.Geometry(0.25, 0.25, 0.25, 0.25, 0.25)
    joint = (ctypes.c_double * 6)()
    assert k5r.joint_reference(ctypes.byref(g), 0.5, 0.0, 0.1, -0.2, 0.3, 0.4, p11, p21, joint) == code
    if code == k5r.OK:
        assert list(joint)[:2] == [p11, p21] and all(math.isfinite(v) for v in joint)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_the_pitch_fall_starts_exactly_at_ninety_degrees(sign):
    """pc_wheeled_condition: |psi| >= pi/2 is FALLEN_PITCH (index 0, psi as value), one double
    short of it is upright.  A body narrower than the wheels (D/2 < R) never touches the floor,
    so only the pitch check decides."""
    from plant.wheeled import SEED, pack

    prm, y = pack(SEED.with_(D=0.05)), np.zeros(K.N_STATE)
    assert 0.05 / 2 < SEED.R
    y[K.PSI] = sign * math.nextafter(math.pi / 2, 0.0)
    assert K.condition(prm, y, kernels.Refusal()) == K.OK
    y[K.PSI] = sign * math.pi / 2
    refusal = kernels.Refusal()
    assert K.condition(prm, y, refusal) == K.FALLEN_PITCH
    assert (refusal.index, refusal.value) == (0, sign * math.pi / 2)


def test_a_non_finite_state_word_is_refused_naming_its_index():
    """Each of the state's words, NaN or infinite, is refused as NONFINITE with its index."""
    from plant.wheeled import SEED, pack

    prm = pack(SEED)
    for i in range(K.N_STATE):
        for bad in (math.nan, -math.inf):
            y = np.zeros(K.N_STATE)
            y[i] = bad
            refusal = kernels.Refusal()
            assert K.condition(prm, y, refusal) == K.NONFINITE and refusal.index == i, (i, bad)


@pytest.mark.parametrize("dt, code", [(2.0 ** -1074, K.OK), (0.0, K.BAD_STEP), (-0.0, K.BAD_STEP),
                                      (-2.0 ** -1074, K.BAD_STEP), (math.nan, K.BAD_STEP)])
def test_the_plain_step_takes_any_finite_positive_step_length(dt, code):
    """pc_wheeled_step's step length must be > 0 and finite (seed 4101 [286]: ``>=`` took a step of
    0): the smallest positive double is accepted, zero of either sign, the largest negative and NaN
    refused by BAD_STEP with index 0 and the length, the state kept."""
    sim = WheeledPendulum(initial=dict(psi=0.05))
    start, calls = sim.y.copy(), K.calls(sim)
    assert calls.step(0.0, 0.0, 0.0, dt, 1) == code
    if code != K.OK:
        value = calls.refusal.value
        assert calls.refusal.index == 0 and (value == dt or math.isnan(dt) and math.isnan(value))
        np.testing.assert_array_equal(sim.y, start)
