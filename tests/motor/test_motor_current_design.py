"""The current controller of appendix C designed at sample times and poles other than the
thesis' (1 ms; 0, 0.6, 0.7), held against a ZOH model computed here with scipy (no
python-control) and the closed-loop polynomial (C.8) multiplied out here."""
import numpy as np
import pytest
from scipy import signal

from motor import Drive, design_current_controller, motor1, motor2
from motor.current_controller import _tf_coefficients
from tests.motor.test_motor_current_control import assert_same_poles, prony_poles

POLES = (0.2, 0.5, 0.8)


def zoh(num, den, T):
    """(N, D) of the ZOH discretisation, D monic, N without leading zeros (scipy.signal)."""
    n, d, _ = signal.cont2discrete((num, den), T, method="zoh")
    n = np.trim_zeros(np.squeeze(n), "f")
    if abs(n[0]) < 1e-14 * np.max(np.abs(n)):
        n = n[1:]
    return n / d[0], d / d[0]


def current_model(p):
    """G_I(s) = (J s + b) / ((L s + R)(J s + b) + kt ke) (B.10), written out here."""
    return [p.J_rotor, p.b], [p.L * p.J_rotor, p.L * p.b + p.R * p.J_rotor, p.R * p.b + p.kt * p.ke]


@pytest.mark.parametrize("T", [5e-4, 2e-3])
@pytest.mark.parametrize("params", [motor1, motor2])
def test_a_design_at_another_sample_time_and_poles_places_them_on_the_zoh_model(params, T):
    """Catches a design that discretises (B.10) at 1 ms or with another hold, has a wrong term
    in G_I, or places the thesis' poles instead of the ones asked for: its model is scipy's
    ZOH of G_I at T and (z - 1)(z - delta) D + (alpha z^2 + beta z + gamma) N is the
    polynomial of the poles asked for and the model's zero."""
    d = design_current_controller(params, T=T, poles=POLES)
    N, D = zoh(*current_model(params), T)
    plant_num = np.trim_zeros(np.squeeze(d.plant.num[0][0]), "f")
    plant_den = np.squeeze(d.plant.den[0][0])
    np.testing.assert_allclose(plant_num / plant_den[0], N, rtol=1e-7)
    np.testing.assert_allclose(plant_den / plant_den[0], D, rtol=1e-9, atol=1e-12)
    zero = -N[1] / N[0]
    closed = np.polyadd(np.polymul(np.polymul([1.0, -1.0], [1.0, -d.delta]), D),
                        np.polymul([d.alpha, d.beta, d.gamma], N))
    np.testing.assert_allclose(closed, np.poly([*POLES, zero]), rtol=0, atol=1e-9)
    assert d.T == T and d.delta == pytest.approx(zero, rel=1e-6)


@pytest.mark.parametrize("T", [5e-4, 2e-3])
def test_the_drive_at_another_sample_time_has_the_designed_locked_rotor_poles(T):
    """Locked rotor (omega = 0): the drive's controller, sampled every T, on 1/(L s + R) has the
    roots of (z - 1)(z - delta) Dl + (alpha z^2 + beta z + gamma) Nl, with Nl/Dl scipy's ZOH of
    1/(L s + R) at T.  Catches a drive whose controller or electrical step uses 1 ms, or
    the thesis' poles, when another T and other poles are asked for."""
    p = motor2
    d = design_current_controller(p, T=T, poles=POLES)
    Nl, Dl = zoh([1.0], [p.L, p.R], T)
    closed = np.polyadd(np.polymul(np.polymul([1.0, -1.0], [1.0, -d.delta]), Dl),
                        np.polymul([d.alpha, d.beta, d.gamma], Nl))
    drive = Drive(p, T=T, poles=POLES)
    v = np.array([drive.step(0.2, 0.0, 0.0, drive.i, T)[1] for _ in range(40)])
    assert np.max(np.abs(v)) < p.v_max                      # linear: never saturated
    assert_same_poles(prony_poles(v, order=3, k0=4), np.roots(closed), atol=1e-6)


def test_tf_coefficients_divide_numerator_and_denominator_by_the_leading_denominator():
    """A transfer function given with a non-monic denominator, 2 (z + 2) / (2 z^2 + 6 z + 8)
    = (z + 2) / (z^2 + 3 z + 4): the same ratio, the denominator monic (what the design's
    coefficient matching assumes), the numerator's leading zeros dropped."""
    import control   # here: python-control takes 1-2 s to import

    num, den = _tf_coefficients(control.tf([0.0, 2.0, 4.0], [2.0, 6.0, 8.0], 1e-3))
    assert num.tolist() == [1.0, 2.0] and den.tolist() == [1.0, 3.0, 4.0]


@pytest.mark.parametrize("poles", [(0.2, 0.5), (0.2, 0.5, 0.6, 0.7), (0.2, 0.5, 1.0), (0.2, -1.0, 0.5),
                                   (1.5, 0.2, 0.5)])
def test_poles_are_refused_unless_three_inside_the_unit_circle(poles):
    """Each clause alone: a count other than three (all inside), or one pole on or outside
    |z| = 1 (the count right): a closed loop with such a pole does not settle."""
    with pytest.raises(ValueError) as info:
        design_current_controller(motor1, T=1e-3, poles=poles)
    assert str(info.value) == f"poles must be three values with |z| < 1, got {[float(p) for p in poles]!r}"


def test_poles_just_inside_the_unit_circle_are_placed():
    d = design_current_controller(motor1, T=1e-3, poles=(-0.999, 0.0, 0.999))
    assert sorted(np.real(d.desired_poles[:3])) == pytest.approx([-0.999, 0.0, 0.999])
