"""The wheeled pendulum's parameters against seed 000, their validation boundaries and the
refusals of the simulator's construction (each names the variable and its value)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from plant.wheeled import POSITIVE, SEED, WheeledParams, WheeledPendulum, pack, upright_mass_matrix


def test_default_parameters_are_seed_000_s_values_and_formulas():
    """Seed 000's parameter list: g, m, R, M, W, D, H as printed; J_w = m R^2/2, L = H/2,
    J_psi = M L^2/3, J_phi = M (W^2 + D^2)/12 computed here from those printed values."""
    p = WheeledParams()
    assert (p.g, p.m, p.R, p.M, p.W, p.D, p.H) == (9.8, 0.03, 0.04, 0.6, 0.14, 0.04, 0.144)
    assert p.J_w == pytest.approx(0.03 * 0.04 * 0.04 / 2.0, rel=1e-14)
    assert p.L == pytest.approx(0.144 / 2.0, rel=1e-14)
    assert p.J_psi == pytest.approx(0.6 * 0.072 * 0.072 / 3.0, rel=1e-14)
    assert p.J_phi == pytest.approx(0.6 * (0.0196 + 0.0016) / 12.0, rel=1e-14)
    assert SEED == p


@pytest.mark.parametrize("name", POSITIVE)
def test_a_positive_parameter_at_exactly_zero_is_refused_by_name_and_value(name):
    """R, M, W, L must be > 0: zero itself is the boundary (a >= would pass it)."""
    with pytest.raises(ValueError, match=rf"^parameter {name} = 0.0 must be > 0$"):
        SEED.with_(**{name: 0.0})


@pytest.mark.parametrize("name", ["g", "m", "J_w", "D", "H", "J_psi", "J_phi"])
def test_a_non_negative_parameter_at_exactly_zero_is_accepted_and_below_it_refused(name):
    """The others must be >= 0: zero is accepted (a > would refuse it), -1e-9 is refused by name."""
    assert getattr(SEED.with_(**{name: 0.0}), name) == 0.0
    with pytest.raises(ValueError, match=rf"^parameter {name} = -1e-09 must be >= 0$"):
        SEED.with_(**{name: -1e-9})


@pytest.mark.parametrize("value", [float("nan"), float("inf"), "0.1"])
def test_a_non_finite_or_non_number_parameter_is_refused_by_name_and_value(value):
    with pytest.raises(ValueError, match=rf"^parameter J_phi = {value!r} is not a finite number$"):
        SEED.with_(J_phi=value)


def test_unknown_parameters_are_refused_by_their_sorted_names():
    with pytest.raises(ValueError, match=r"unknown pendulum parameter\(s\) \['a', 'b'\]"):
        SEED.with_(b=1.0, a=1.0, m=0.1)


def test_upright_mass_matrix_is_seed_18_at_zero_pitch_with_asymmetric_parameters():
    """Seed (18) at psi = 0: M11 = (2m + M) R^2 + 2 J_w, M12 = M R L, M22 = M L^2 + J_psi,
    and the yaw inertia m W^2/2 + J_phi + W^2/(2 R^2) J_w (the wheels' m W^2/2 of (14)); the
    parameters all differ so that a dropped or swapped term shows."""
    p = SEED.with_(m=0.5, R=0.3, J_w=0.7, M=2.0, W=1.1, L=0.9, J_psi=0.13, J_phi=0.17)
    pitch, m33 = upright_mass_matrix(p)
    m11 = (2 * 0.5 + 2.0) * 0.09 + 2 * 0.7
    np.testing.assert_allclose(pitch, [[m11, 2.0 * 0.3 * 0.9], [2.0 * 0.3 * 0.9, 2.0 * 0.81 + 0.13]], rtol=1e-14)
    assert m33 == pytest.approx(0.5 * 1.21 / 2 + 0.17 + 1.21 / (2 * 0.09) * 0.7, rel=1e-14)


def test_pack_refuses_an_unknown_model_naming_it_and_the_valid_ones():
    with pytest.raises(ValueError, match=r"^model = 'Exact'; valid: exact, seed$"):
        pack(SEED, "Exact")


@pytest.mark.parametrize("kwargs, text", [
    (dict(substeps=0), r"^parameter substeps = 0 must be an integer in \[1, \d+\]$"),
    (dict(substeps=2.0), r"^parameter substeps = 2.0 must be an integer"),
    (dict(encoder_counts=0), r"^parameter encoder_counts = 0 must be a positive integer$"),
    (dict(initial=dict(alpha=0.1)), r"^unknown initial state 'alpha'; valid: theta, "),
    (dict(initial=dict(x=math.inf)), r"^initial x = inf is not finite$"),
])
def test_construction_refusals_name_the_variable_and_the_value(kwargs, text):
    with pytest.raises(ValueError, match=text):
        WheeledPendulum(**kwargs)


def test_one_encoder_count_per_turn_is_the_smallest_accepted():
    """encoder_counts > 0: 1 is the boundary (a full turn per count)."""
    assert WheeledPendulum(encoder_counts=1).count == pytest.approx(2.0 * math.pi, rel=1e-15)


def test_a_yaw_rate_with_the_yaw_locked_is_refused_naming_it_and_its_value():
    """yaw = False locks phi' = 0: a start with dphi != 0 contradicts it (BadValue: name, value)."""
    with pytest.raises(ValueError) as caught:
        WheeledPendulum(yaw=False, initial=dict(dphi=0.25))
    assert (caught.value.name, caught.value.value) == ("dphi", 0.25)
    assert str(caught.value) == "initial dphi = 0.25 with the yaw locked (yaw = false) must be 0"
    assert WheeledPendulum(yaw=False, initial=dict(dtheta=0.25)).y[3:].any()   # other rates are free


def test_a_start_with_the_body_on_the_floor_is_refused_as_fallen_floor():
    """A body 0.2 m deep touches the floor at psi = asin(R / (D/2)) = asin(0.4), 0.41 rad,
    before 90 degrees: a start at 0.5 rad is no standing robot, and the reason says why."""
    with pytest.raises(ValueError) as caught:
        WheeledPendulum(SEED.with_(D=0.2), initial=dict(psi=-0.5))
    assert (caught.value.name, caught.value.value) == ("psi", -0.5)
    assert str(caught.value) == "initial psi = -0.5 rad is no standing robot (fallen_floor)"
    WheeledPendulum(SEED.with_(D=0.2), initial=dict(psi=-0.4))
