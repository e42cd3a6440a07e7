"""The position law's delay compensation (kernels/src/law.c ``pc_law_predict``, the law's
``predict``; docs/contract.md "Delay compensation") against a double integrator integrated
here, and the option off against the law as it was.
"""
import numpy as np
import pytest

from controller import law
from controller.position import PositionController
from controller.strategies import get_strategy
from plant import get_preset

H = 1e-3


def double_integrator(accelerations, q0, v0, h=H):
    """Exact (q, v) at every period's start of a double integrator whose acceleration is
    ``accelerations[k]`` (rows of 2) over period k: q += h v + h^2 a / 2, v += h a."""
    q, v = [np.array(q0, float)], [np.array(v0, float)]
    for a in accelerations:
        q.append(q[-1] + h * v[-1] + 0.5 * h * h * a)
        v.append(v[-1] + h * a)
    return np.array(q), np.array(v)


@pytest.mark.parametrize("a, b", [(2, 3), (1, 1), (3, 0), (0, 2), (4, 2), (8, 8)])
def test_prediction_is_the_double_integrators_state_at_the_commands_time(a, b):
    """Commands c_k, a plant that follows c_k - d (a constant part d it does not follow, given
    as the bias): from the angle a periods and the rate b periods before period k and the
    commands since, the prediction is the state at k to rounding.  Catches the commands taken
    in the wrong order or shifted by one, a missing h^2/2 term, the bias with the wrong sign,
    and the rates not brought to the angles' time (a > b goes back)."""
    rng = np.random.default_rng(a * 10 + b)
    commands = rng.normal(0.0, 50.0, (30, 2))
    d = np.array([3.0, -7.0])
    q, v = double_integrator(commands - d, (0.3, 2.1), (-0.4, 0.9))
    for k in range(10, 30):
        past = commands[k - 1::-1][:max(a, b, 1)]          # newest first: over [k-1, k], [k-2, k-1], ...
        measured = (*q[k - a], *v[k - b])
        joint = law.predict(measured, past, d, a, b, H)
        np.testing.assert_allclose(joint, (*q[k], *v[k]), rtol=0, atol=1e-12)
    if a or b:   # the prediction is not the measurement: the test can fail
        assert not np.allclose(law.predict(measured, past, d, a, b, H), measured, atol=1e-6)


def _run(delay_compensation, steps=40):
    """PDx, TCMDq samples on a pose moving off the circle: the outputs and the law's state."""
    from controller.kinematics import Kinematics
    from controller.trajectories import get_trajectory

    bench, circle = get_preset("bench"), get_trajectory("circle")
    kin = Kinematics(bench)
    rows = []
    for name in ("PDx", "TCMDq"):
        c = PositionController(bench, get_strategy(name), model="exact", delay_compensation=delay_compensation)
        for k in range(steps):
            t = k * H
            r = circle(t)
            angles = kin.inverse(r.x + 0.001 * np.sin(30 * t), r.y)
            rows.append(c.step_with_errors(t, angles[0], angles[2], 0.2 * np.cos(9 * t), -0.1, 0.5, 0.3,
                                           r.x, r.y, r.dx, r.dy, r.ddx, r.ddy))
    return np.array(rows)


def test_compensation_changes_the_commands_and_zero_is_the_law_without_it():
    """(0, 0) is the law without compensation (the default), bit for bit; (2, 3) changes the
    commands once it has commanded.  Catches an option that is always on, or never on."""
    off, default, on = _run((0, 0)), _run(PositionController.__init__.__defaults__[-1]), _run((2, 3))
    assert np.array_equal(off, default)
    assert not np.allclose(on[5:], off[5:])


@pytest.mark.parametrize("value", [(9, 0), (0, -1), (1.5, 1), (True, 0), (2,)])
def test_compensation_out_of_range_is_refused_by_name(value):
    """Catches a compensation beyond the kept commands (which would read past the state)."""
    with pytest.raises(ValueError, match="delay_compensation"):
        PositionController(get_preset("bench"), get_strategy("PDq"), delay_compensation=value)
