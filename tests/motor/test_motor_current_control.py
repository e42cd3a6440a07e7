"""Discrete current controller (appendix C, 7.2.10) and the closed current loop of the drive."""

import math

import control
import numpy as np
import pytest

from motor import Drive, current_transfer_function, design_current_controller, motor1, motor2

from tests.support.motor_loops import current_step

T = 1e-3


def prony_poles(y, order, k0):
    """Poles of the linear recurrence fitted to the increments of a step response."""
    dy = np.diff(y)
    rows = np.array([dy[k - order:k][::-1] for k in range(k0, len(dy))])
    a = np.linalg.lstsq(rows, -dy[k0:], rcond=None)[0]
    return np.roots(np.r_[1.0, a])


def assert_same_poles(found, wanted, atol):
    found, wanted = np.asarray(found, complex), np.asarray(wanted, complex)
    assert len(found) == len(wanted)
    for p in wanted:                                  # greedy matching, robust to ordering
        k = np.argmin(np.abs(found - p))
        assert abs(found[k] - p) < atol, (found, wanted)
        found = np.delete(found, k)


@pytest.mark.parametrize("params", [motor1, motor2])
def test_design_solves_printed_matrix_form(params):
    """Coefficients satisfy (C.12) as printed, with A, B, C, D from python-control's ZOH (C.3)."""
    d = design_current_controller(params)
    num = np.squeeze(d.plant.num[0][0])
    den = np.squeeze(d.plant.den[0][0]) / np.squeeze(d.plant.den[0][0])[0]
    A, B = num[-2:] / np.squeeze(d.plant.den[0][0])[0]
    C, D = den[1], den[2]
    c3, c2, c1, c0 = np.poly(d.desired_poles)[1:]
    M = np.array([[0, 0, B, D], [0, B, A, C - D], [B, A, 0, 1 - C], [A, 0, 0, -1]])
    rhs = np.array([c0, c1 + D, c2 + C - D, c3 + 1 - C])
    np.testing.assert_allclose(M @ [d.alpha, d.beta, d.gamma, d.delta], rhs, atol=1e-12)
    # the fourth pole sits on the plant zero, so delta cancels it
    assert d.delta == pytest.approx(-B / A, rel=1e-9)  # (C.12): cond ~ 1e6 since A + B ~ 1e-3
    assert_same_poles(d.closed_loop_poles, [0.0, 0.6, 0.7, -B / A], atol=1e-9)


def test_zoh_model_matches_continuous_step_response():
    """G_I(z) from python-control equals the sampled step response of (B.10)."""
    d = design_current_controller(motor1)
    t = T * np.arange(50)
    _, y_c = control.step_response(current_transfer_function(motor1), t)
    _, y_d = control.step_response(d.plant, t)
    np.testing.assert_allclose(y_d, y_c, rtol=1e-6, atol=1e-9)


def free_rotor_step(params, substeps, n=3000, i_ref=0.1):
    """Current-mode step with a free rotor (ideal inertia J_rotor, mu = 0: the design model B.10).

    The drive is fed back its true current at each sample; omega is integrated here
    with ``substeps`` co-simulation steps per controller period.
    """
    p = params.with_(mu=0.0)
    drive, h, omega = Drive(p), T / substeps, 0.0
    v = np.empty(n)
    for k in range(n):
        for _ in range(substeps):
            tau, v[k], _ = drive.step(i_ref, 0.0, omega, drive.i, h)
            omega += h * tau / p.J_rotor
    return v


@pytest.mark.parametrize("params", [motor1, motor2])
def test_closed_loop_poles_identified_from_drive_response(params):
    """Poles fitted to the drive's own voltage step response are the designed 0, 0.6, 0.7, z0.

    With omega held over a co-simulation step the coupling error is O(h^2) in the poles
    (measured: ~5e-3 at h = T, ~2e-4 at T/5, ~1.4e-5 at T/20); h = T/20 here.
    """
    design = design_current_controller(params)
    found = prony_poles(free_rotor_step(params, substeps=20), order=4, k0=5)
    assert_same_poles(found[np.abs(found) > 0.1], design.desired_poles[1:], atol=1e-4)
    assert np.min(np.abs(found)) < 1e-4
    assert_same_poles(found, design.desired_poles, atol=1e-4)


@pytest.mark.parametrize("params", [motor1, motor2])
def test_locked_rotor_loop_poles_exact(params):
    """Locked rotor: the plant is 1/(Ls+R); the drive's loop has exactly the poles
    python-control predicts for K(z) with its ZOH model (no coupling error)."""
    design = design_current_controller(params)
    locked = control.c2d(control.tf([1.0], [params.L, params.R]), T, "zoh")
    wanted = control.poles(control.feedback(design.controller * locked, 1))
    drive = Drive(params)
    v = np.array([drive.step(1.0, 0.0, 0.0, drive.i, T)[1] for _ in range(40)])
    assert_same_poles(prony_poles(v, order=3, k0=4), wanted, atol=1e-7)


@pytest.mark.parametrize("kind", ["static", "dynamic"])
@pytest.mark.parametrize("omega", [0.0, 50.0])
@pytest.mark.parametrize("params", [motor1, motor2])
def test_current_step_with_observer_settles(params, omega, kind):
    """Within 1 % from 20 ms on, peak under 2 A (locked rotor and constant 50 rad/s)."""
    i = current_step(params, kind, omega)
    assert np.all(np.abs(i[20:] - 1.0) <= 0.01)
    assert i.max() < 2.0


def test_static_observer_rings_on_motor2():
    """Documented: with the static observer the loop sees 1/(R z), not G_I(z); the design
    then leaves a real pole at -0.79 for motor 2 (-0.48 for motor 1), visible as ringing.
    The dynamic observer removes it."""
    for params, pole in ((motor1, -0.483), (motor2, -0.794)):
        d = design_current_controller(params)
        seen = control.tf([1.0 / params.R], [1.0, 0.0], T)
        poles = control.poles(control.feedback(d.controller * seen, 1))
        assert min(poles.real) == pytest.approx(pole, abs=1e-3)
    di = np.diff(current_step(motor2, "static", 0.0)[1:12])
    assert np.all(di[:-1] * di[1:] < 0)                   # alternating increments
    assert np.all(np.diff(current_step(motor2, "dynamic", 0.0)[1:5]) > 0)


def test_anti_windup_leaves_saturation_at_once():
    """Unreachable 40 A request (needs 44 V) for 50 ms, then 1 A: voltage leaves
    saturation at the first sample and the current does not overshoot."""
    drive = Drive(motor1)
    v = [drive.step(40.0, 0.0, 0.0, drive.i, T)[1] for _ in range(50)]
    assert v[-1] == 24.0
    out = [drive.step(1.0, 0.0, 0.0, drive.i, T) for _ in range(40)]
    assert out[0][1] < 24.0
    i = np.array([o[2] for o in out])
    assert np.all(np.abs(i[25:] - 1.0) < 0.01) and i[5:].max() < 1.2


def test_substeps_hold_controller_voltage_over_period():
    """Catches a controller that recomputes its voltage at every sub-step instead of once per period T."""
    drive = Drive(motor1)
    v = [drive.step(1.0, 0.0, 0.0, drive.i, T / 4)[1] for _ in range(8)]
    assert v[0] == v[1] == v[2] == v[3] != v[4] == v[7]
    with pytest.raises(ValueError, match="i_hat must be a finite number, got inf"):
        drive.step(1.0, 0.0, 0.0, math.inf, T)


def test_design_params_keep_the_controller_of_the_real_motor():
    """Catches a drive that designs its current controller from the simulated motor instead of design_params."""
    from motor import get_motor_preset

    real = get_motor_preset("motor1")
    frictionless = real.with_(b=0.0)
    tuned = Drive(frictionless, design_params=real)
    coefficients = ("alpha", "beta", "gamma", "delta")
    assert ([getattr(tuned.controller.design, c) for c in coefficients]
            == [getattr(Drive(real).controller.design, c) for c in coefficients])
    assert tuned.params.b == 0.0
