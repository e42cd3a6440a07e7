"""identify()'s input checks (motor/identification.py), column by column: each refusal names
the column, the entry and its value, and what is required."""
import math

import numpy as np
import pytest

from motor import identify
from motor.identification import inertia_from_pole, normal_equations_friction, pole_from_settling_time

GOOD = dict(u=[1.0, 2.0, 3.5], i=[0.5, 0.6, 0.8], omega=[10.0, 30.0, 55.0])


@pytest.mark.parametrize("change, message", [
    (dict(i="abc"), "i must be a sequence of numbers, got 'abc'"),
    (dict(omega=[[1.0, 2.0], [3.0, 4.0]]), "omega must be one-dimensional, got shape (2, 2)"),
    (dict(u=5.0), "u must be one-dimensional, got shape ()"),
    (dict(i=[0.5, math.inf, math.nan]), "i[1] must be a finite number, got inf"),   # the first one
    (dict(omega=[10.0, math.nan, 55.0]), "omega[1] must be a finite number, got nan"),
    (dict(i=[0.5, 0.6]), "u, i and omega must have the same length, got {'u': 3, 'i': 2, 'omega': 3}"),
    (dict(u=[1.0], i=[0.5], omega=[10.0]), "need at least 2 data points, got 1"),
    (dict(omega=[10.0, -0.0, -3.0]), "omega[1] must be > 0 (D.10 holds for omega > 0), got -0.0"),
    (dict(settling_time=0.2, L=-1e-3), "L must be >= 0, got -0.001"),
])
def test_each_bad_input_is_refused_naming_its_column_entry_and_value(change, message):
    """Catches a check that names another column or entry, lets a column through (the length
    check inverted refuses every good call; one left out lets a short column reach the fit), or
    a message without the value."""
    with pytest.raises(ValueError) as caught:
        identify(**{**GOOD, **change})
    assert str(caught.value) == message
    identify(**GOOD)                      # the same call without the change goes through



@pytest.mark.parametrize("p, R, L, kt, ke, b", [(-4 / 0.207, 1.10098, 0.667e-3, 0.055984, 0.0513822, 0.000122595),
                                                (-3.0, 2.0, 0.01, 0.3, 0.2, 0.0),
                                                (-50.0, 6.69, 0.0, 0.4, 0.4, 0.0022)])
def test_the_inertia_puts_the_pole_on_the_characteristic_equation(p, R, L, kt, ke, b):
    """J from (D.16) makes (L p + R)(J p + b) + kt ke vanish at p (the equation written here),
    with and without L and b; pole_from_settling_time is -4 / t.  Catches a term dropped or a
    sign flipped in J."""
    J = inertia_from_pole(p, R, L, kt, ke, b)
    assert J > 0.0
    assert (L * p + R) * (J * p + b) + kt * ke == pytest.approx(0.0, abs=1e-15 * (abs(kt * ke) + 1.0))
    assert pole_from_settling_time(0.25) == -16.0


@pytest.mark.parametrize("p, R, L, kt, ke, b, message", [
    (-4.0, 2.0, 0.25, 0.0, 0.3, 0.0, "settling time gives a non-positive inertia J=0.0 (pole p=-4.0)"),
    (-4.0, 2.0, 0.25, 0.3, 0.0, 0.0, "settling time gives a non-positive inertia J=0.0 (pole p=-4.0)"),
    (-4.0, 1.0, 0.5, 0.5, 0.5, 0.0, "settling time gives a non-positive inertia J=-0.0625 (pole p=-4.0)"),
    (-4.0, 2.0, 0.5, 0.3, 0.3, 0.0, "L p + R = 0 for p=-4.0: J undetermined"),
    (-4.0, 2.0, 0.25, math.nan, 0.3, 0.0, "settling time gives a non-positive inertia J=nan (pole p=-4.0)"),
])
def test_an_inertia_that_is_not_positive_is_refused_word_for_word(p, R, L, kt, ke, b, message):
    """J = 0 exactly (no torque constant: kt = 0 or ke = 0, b = 0), J < 0 (a pole beyond the
    electrical one, L p + R < 0), L p + R = 0 and a NaN J are refused with J and the pole.
    Catches ``J > 0`` loosened to ``J >= 0``, the L p + R check dropped, and a message without
    the values."""
    with pytest.raises(ValueError) as info:
        inertia_from_pole(p, R, L, kt, ke, b)
    assert str(info.value) == message


def _friction_condition(delta):
    """cond of (D.11)'s G for the two speeds 1 and 1 + delta rad/s."""
    G, _ = normal_equations_friction(np.array([1.0, 0.5]), np.array([1.0, 1.0 + delta]), 0.05)
    return np.linalg.cond(G)


@pytest.mark.parametrize("target, refused", [(1.5e12, True), (0.5e12, False)])
def test_normal_equations_past_a_condition_of_1e12_are_refused_as_singular_and_below_solved(target, refused):
    """Two speeds delta apart: G of (D.11) has det delta^2, so its condition grows as
    1/delta^2; delta is chosen here to put it at ``target``, either side of the 1e12 the
    identification takes for singular (the electrical equations stay well conditioned)."""
    delta = 6.0 / math.sqrt(target)     # cond ~ trace^2 / det = 36 / delta^2
    for _ in range(60):                 # refine on the computed condition (it is monotone in delta)
        delta *= math.sqrt(_friction_condition(delta) / target)
    cond = _friction_condition(delta)
    assert (cond > 1e12) == refused and (cond < 2e12 if refused else cond > 0.25e12)
    data = dict(u=[1.0, 2.0], i=[1.0, 0.5], omega=[1.0, 1.0 + delta])
    if refused:
        with pytest.raises(ValueError, match=r"data do not determine mu and b: the normal equations are singular"):
            identify(**data)
    else:
        r = identify(**data)
        assert math.isfinite(r["mu"]) and math.isfinite(r["b"])
