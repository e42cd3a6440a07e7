"""ActuatedPlant.kernel_refusal (plant/actuated.py): the refusal of a compiled actuated step for
each status the kernel returns, read back (reason, variable, value, message) against the texts
of the plant's own checks: a non-finite plant state names its state word, a non-finite current
the drive's current, a diverged or singular step the plant's measure; the state is kept."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from motor import Drive, get_motor_preset
from plant import IntegratorSettings, PlantError, PlantSimulator, fast5r, get_preset
from plant.actuated import ActuatedPlant

START = (-0.002, 0.108)
DT = 1e-3


def actuated():
    sim = PlantSimulator(get_preset("bench"), *START)
    return ActuatedPlant(sim, [(j, Drive(get_motor_preset(f"motor{j}"))) for j in (1, 2)])


@pytest.mark.parametrize("status, index, value, variable, words", [
    (fast5r.NONFINITE_STATE, 5, math.nan, "state[5]", "state became non-finite in the step from t = 0 s ("),
    (fast5r.NONFINITE_STATE, 13, math.inf, "state[13]", "state became non-finite in the step from t = 0 s ("),
    (fast5r.NONFINITE_STATE, 14, math.nan, "i1", "armature currents [nan, 0.0] after the step from t = 0 s ("),
    (fast5r.NONFINITE_STATE, 15, math.inf, "i2", "armature currents [0.0, inf] after the step from t = 0 s ("),
    (fast5r.DIVERGED, 0, 2.5e-3, "residual", "loop-closure residual 0.0025 m"),
    (fast5r.SINGULAR, 2, 1e-9, "distal links (parallel)", "t = 0.001 s"),
])
def test_each_kernel_status_is_the_plants_refusal_naming_its_word(status, index, value, variable, words):
    """Catches a refusal that takes a plant state word for a current (or the other way round),
    names another word, value or status, or changes the state."""
    a = actuated()
    state = a.state()
    trial = state.copy()
    trial[index] = value if index >= fast5r.PLANT_STATES or status == fast5r.NONFINITE_STATE else trial[index]
    refusal = kernels.Refusal(code=status, index=index, value=value)
    exc = a.kernel_refusal(status, refusal, trial, (0.5, -0.5), (0.0, 0.0), (0.0, 0.0), DT)
    assert isinstance(exc, PlantError)
    record = exc.record()
    assert record["variable"] == variable, record
    assert record["value"] == value or math.isnan(value) and math.isnan(record["value"])
    assert words in str(exc), str(exc)
    assert ("V held" in str(exc)) == (status != fast5r.SINGULAR), str(exc)      # the voltages a step held
    assert np.array_equal(a.state(), state)


@pytest.mark.parametrize("kernel", ["fast", "general"])
@pytest.mark.parametrize("name, joint", [("i_ref", 1), ("i_ref", 2), ("i_hat", 1), ("i_hat", 2),
                                         ("v_ref", 1), ("v_ref", 2)])
def test_each_non_finite_input_is_refused_by_its_name_on_both_paths(kernel, name, joint):
    """A NaN in any one of the six inputs (the other five finite and non-zero, i_hat not equal to
    i_ref) is refused word for word by its name and joint, through the one C call (the default)
    and the Python composition (the general kernel), the state and the drives kept.  Catches the
    compiled step's refusal checking one input in place of another (i_ref passed for i_hat),
    the joints mixed up, and a path that names nothing."""
    from plant import IntegratorSettings

    sim = PlantSimulator(get_preset("bench"), *START, IntegratorSettings(kernel=kernel))
    a = ActuatedPlant(sim, [(j, Drive(get_motor_preset(f"motor{j}"))) for j in (1, 2)])
    assert a._one_call == (kernel == "fast")
    inputs = {"i_ref": [0.5, -0.4], "i_hat": [0.1, 0.2], "v_ref": [1.0, -2.0]}
    a.step(inputs["i_ref"], inputs["i_hat"], inputs["v_ref"], DT)
    inputs[name][joint - 1] = math.nan
    state, currents = a.state(), a.currents
    with pytest.raises(ValueError) as caught:
        a.step(inputs["i_ref"], inputs["i_hat"], inputs["v_ref"], DT)
    assert str(caught.value) == f"input {name}{joint} = nan is not finite"
    assert np.array_equal(a.state(), state) and a.currents == currents


def _at_the_stability_limit(h, R):
    """The inductance L that makes R h / L exactly RK4_REAL_STABILITY in doubles (the
    plant's own x), and the next one down (x one step past it)."""
    from plant.simulator import RK4_REAL_STABILITY as limit
    L = R * h / limit
    for _ in range(8):      # a few ulps either way
        x = R * h / L
        if x == limit:
            break
        L = np.nextafter(L, math.inf if x > limit else 0.0)
    assert R * h / L == limit
    smaller = np.nextafter(L, 0.0)
    while R * h / smaller == limit:
        smaller = np.nextafter(smaller, 0.0)
    return float(L), float(smaller)


def test_an_rk4_step_exactly_at_the_armature_stability_limit_is_taken_and_one_past_it_refused():
    """R h / L = 2.785... is the x where |R(-x)| = 1 (test_plant_integrators.py): marginally
    stable, so the plant takes the step; the next representable x beyond it is refused."""
    R, h = get_motor_preset("motor1").R, DT
    L, smaller = _at_the_stability_limit(h, R)
    settings = IntegratorSettings(kernel="fast", substeps=1)
    for L_drive, refused in ((L, False), (smaller, True)):
        sim = PlantSimulator(get_preset("bench"), *START, settings)
        a = ActuatedPlant(sim, [(1, Drive(get_motor_preset("motor1").with_(L=L_drive), mode="voltage"))])
        if refused:
            with pytest.raises(PlantError, match=r"drive on joint 1: RK4 steps of 0.001 s are unstable"):
                a.step((0.0,), (0.0,), (0.0,), DT)
        else:
            a.step((0.0,), (0.0,), (0.0,), DT)
            assert sim.time == DT


@pytest.mark.parametrize("joints", [[3], [0, 1], [1, 1], [2, 2], [1, 2, 1]])
def test_a_drive_on_no_actuated_joint_or_a_joint_driven_twice_is_refused_naming_the_joints(joints):
    """The 5R's actuated joints are 1 and 2, each driven at most once: a joint outside them (with
    no joint repeated) and a repeated joint (each one valid) are each refused on their own, word
    for word; 1, 2, both, and both the other way round are taken."""
    sim = PlantSimulator(get_preset("bench"), *START)
    with pytest.raises(ValueError) as caught:
        ActuatedPlant(sim, [(j, Drive(get_motor_preset("motor1"))) for j in joints])
    assert str(caught.value) == f"drive joints must be 1 and/or 2, each at most once, got {joints}"
    for taken in ([1], [2], [1, 2], [2, 1]):
        assert [j for j, _ in ActuatedPlant(sim, [(j, Drive(get_motor_preset("motor1"))) for j in taken]).drives] \
            == taken
