"""LuGre friction (motor/friction.py) against its published behaviour.

Canudas de Wit, Olsson, Åström, Lischinsky (IEEE TAC 1995), with the paper's example: a 1 kg
mass, σ0 = 1e5 N/m, σ1 = √1e5 N s/m, σ2 = 0.4 N s/m, Fc = 1 N, Fs = 1.5 N, vs = 0.001 m/s.
The oracle is the paper's ODE (1)-(4) written here again with numpy and integrated by scipy's
LSODA at rtol 1e-8: it shares no code with motor/friction.py.  Our model is stepped the way the
drive steps it (:func:`scenarios.examples.friction_demo.push`): the speed held over a step h, the bristle
state solved exactly (:func:`motor.friction.advance`), the mass integrated with the step's mean
friction.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from motor import friction as fr
from scenarios.examples.friction_demo import PAPER, RAMP, SINE, SPRING, push

MASS = 1.0
H = 1e-5          # the stepped model's step: c = h σ1 / m = 3e-3, far inside the coupling's band


def paper_rhs(t, s, force):
    """(1)-(4) for a mass pushed by force(t) [N]: state (x, v, z)."""
    x, v, z = s
    g = PAPER["Fc"] + (PAPER["Fs"] - PAPER["Fc"]) * np.exp(-(v / PAPER["omega_s"]) ** 2)
    dz = v - PAPER["sigma0"] * abs(v) * z / g
    friction = PAPER["sigma0"] * z + PAPER["sigma1"] * dz + PAPER["sigma2"] * v
    return [v, (force(t, x) - friction) / MASS, dz]


def reference(force, t_end, times):
    sol = solve_ivp(paper_rhs, (0.0, t_end), [0.0, 0.0, 0.0], args=(force,), method="LSODA",
                    rtol=1e-8, atol=1e-12, dense_output=True, max_step=1e-3)
    assert sol.status == 0, sol.message
    return sol.sol(times)


def stepped(kind, a, b, t_end):
    return push(kind, a, b, t_end, h=H, mass=MASS)


def test_presliding_is_an_elastic_displacement_with_hysteresis():
    """A force below Fc (0.5 N sin πt) moves the mass by about F/σ0 and no more; the way back
    differs from the way out (hysteresis) and the displacement returns to ~0 with the force."""
    amplitude = 0.5
    out, t = stepped(SINE, amplitude, math.pi, 2.0)
    x = out[:, 0]
    ref = reference(lambda s, _: amplitude * math.sin(math.pi * s), 2.0, t[::100])
    peak = amplitude / PAPER["sigma0"]
    assert np.abs(x[::100] - ref[0]).max() < 0.02 * peak
    assert peak <= x.max() < 1.3 * peak                     # F/σ0, stiffened by no sliding
    up, down = np.argmin(abs(t - 1 / 6)), np.argmin(abs(t - 5 / 6))   # both at F = 0.25 N
    assert x[down] - x[up] > 0.1 * peak                     # hysteresis
    assert abs(x[-1]) < 0.05 * peak                         # reversible


def test_break_away_force_is_fs_for_a_slow_ramp_and_falls_with_the_rate():
    """A ramped force starts the motion (v > vs) near Fs when slow; the faster the ramp, the
    lower the force at break-away (the rate dependence the paper reproduces)."""
    forces = []
    for rate in (0.1, 1.0, 10.0):
        out, t = stepped(RAMP, rate, 0.0, 2.0 / rate)
        k = int(np.argmax(out[:, 1] > PAPER["omega_s"]))
        forces.append(rate * t[k])
        if rate == 1.0:
            ref = reference(lambda s, _: rate * s, 2.0 / rate, t)
            k_ref = int(np.argmax(ref[1] > PAPER["omega_s"]))
            assert abs(forces[-1] - rate * t[k_ref]) < 2e-3 * PAPER["Fs"]
    assert 0.98 * PAPER["Fs"] < forces[0] <= PAPER["Fs"]
    assert forces[0] > forces[1] > forces[2] > PAPER["Fc"]


def _slips(v):
    """Indices where the mass leaves a stick phase (|v| < vs)."""
    stuck = np.abs(v) < PAPER["omega_s"]
    return np.flatnonzero(stuck[:-1] & ~stuck[1:])


def test_stick_slip_on_a_spring_pulled_at_0_1_m_s():
    """k = 2 N/m pulled at 0.1 m/s: the mass sticks until the spring reaches ~Fs, slips, sticks
    again — periodically; the oracle gives the same slip times."""
    k, pull = 2.0, 0.1
    out, t = stepped(SPRING, k, pull, 15.0)
    slips = _slips(out[:, 1])
    assert len(slips) >= 2
    spring = k * (pull * t - out[:, 0])
    assert np.all(np.abs(spring[slips] - PAPER["Fs"]) < 0.02 * PAPER["Fs"])
    ref = reference(lambda s, x: k * (pull * s - x), 15.0, t[::10])
    ref_slips = t[::10][_slips(ref[1])]
    assert len(ref_slips) == len(slips)
    assert np.abs(t[slips] - ref_slips).max() < 0.01


def test_steady_sliding_above_the_critical_pull_speed():
    """At 0.5 m/s the same spring-mass slides steadily: the speed's oscillation dies out."""
    k, pull = 2.0, 0.5
    out, t = stepped(SPRING, k, pull, 30.0)
    v = out[:, 1]
    late = v[t > 25.0]
    assert late.min() > 0.9 * pull and late.max() < 1.1 * pull
    early = v[(t > 5.0) & (t < 10.0)]
    assert np.ptp(late) < 0.1 * np.ptp(early)


@pytest.mark.parametrize("omega, h, z0", [(0.3, 1e-3, 2e-4), (-2.0, 1e-3, 2e-4), (1e-6, 1e-3, 2e-4),
                                           (5e-5, 1e-3, 2e-4), (0.0, 1e-3, 2e-4), (5e-4, 1e-3, 0.0)])
def test_exact_step_matches_the_ode_with_the_speed_held(omega, h, z0):
    """advance(): z(h) and the step's mean friction against scipy on (1) with ω constant
    (large, tiny r h: both branches of φ1, φ2; from z0 = 0 at r h = 7e-4 the mean deflection
    is ω h φ2 alone, so φ2's series is seen to its first-order term)."""
    model = fr.LuGre(Fc=0.05, Fs=0.07, omega_s=0.1, sigma0=100.0, sigma1=0.15, sigma2=1e-4)
    f = fr.new_lugre(model)

    def rhs(t, s):
        z = s[0]
        g = model.Fc + (model.Fs - model.Fc) * math.exp(-(omega / model.omega_s) ** 2)
        return [omega - model.sigma0 * abs(omega) * z / g, z]

    sol = solve_ivp(rhs, (0.0, h), [z0, 0.0], method="LSODA", rtol=1e-12, atol=1e-16)
    z_ref, integral = sol.y[0, -1], sol.y[1, -1]
    mean_ref = model.sigma0 * integral / h + model.sigma1 * (z_ref - z0) / h + model.sigma2 * omega
    z, f_end, f_mean = fr.advance(f, z0, omega, h)
    assert z == pytest.approx(z_ref, rel=1e-8, abs=1e-15)
    assert f_mean == pytest.approx(mean_ref, rel=1e-7, abs=1e-13)
    # F at the step's end, (4) with (1) at z(h), written here again
    g = model.Fc + (model.Fs - model.Fc) * math.exp(-(omega / model.omega_s) ** 2)
    rate_ref = omega - model.sigma0 * abs(omega) * z_ref / g
    end_ref = model.sigma0 * z_ref + model.sigma1 * rate_ref + model.sigma2 * omega
    assert f_end == pytest.approx(end_ref, rel=1e-7, abs=1e-13)
    assert fr.friction_force(f, z, omega) == f_end
    assert fr.bristle_rate(f, z, omega) == pytest.approx(rate_ref, rel=1e-6, abs=1e-12)


def test_static_map_is_the_stribeck_curve():
    """At constant speed F tends to sign(ω) G(ω) + σ2 ω (the paper's (5))."""
    model = fr.LuGre(**PAPER)
    f = fr.new_lugre(model)
    for v in (-0.01, -1e-3, 5e-4, 2e-3, 0.1):
        z, f_end, _ = fr.advance(f, 0.0, v, 10.0)
        g = model.Fc + (model.Fs - model.Fc) * math.exp(-(v / model.omega_s) ** 2)
        assert f_end == pytest.approx(math.copysign(g, v) + model.sigma2 * v, rel=1e-9)
        # the deflection it settles at, both directions: sign(ω) G(ω)/σ0
        assert fr.steady_deflection(f, v) == pytest.approx(z, rel=1e-12)
        assert fr.steady_deflection(f, v) == pytest.approx(math.copysign(g, v) / model.sigma0, rel=1e-12)


@pytest.mark.parametrize("field, value, words", [
    ("sigma0", -5.0, "sigma0 = -5.0 must be > 0"),
    ("sigma1", -0.1, "sigma1 = -0.1 must be >= 0"),
    ("omega_s", 0.0, "omega_s = 0.0 must be > 0"),
    ("Fs", 0.5, "Fs (mu_s) = 0.5 must be >= the Coulomb torque Fc (mu) = 1.0"),
    ("Fc", 0.0, "Fc (mu) = 0.0 must be > 0"),
    ("sigma2", math.nan, "sigma2 (b) = nan must be a finite number"),
])
def test_bad_parameters_are_named(field, value, words):
    """Catches a LuGre parameter check that is missing or whose message does not name the field and its value."""
    with pytest.raises(ValueError, match=words.replace("(", r"\(").replace(")", r"\)")):
        fr.LuGre(**{**PAPER, field: value})


@pytest.mark.parametrize("x", [1e-9, 1e-6, 1e-4, 5e-4, 9.99e-4, 1e-3, 1.0001e-3, 2e-3, 1e-2, 0.1, 1.0, 10.0, 1e3])
def test_phi_functions_match_a_50_digit_evaluation(x):
    """φ1(x) = (1 − e^{−x})/x and φ2(x) = (x − 1 + e^{−x})/x² of the exact step, against
    50-digit decimal arithmetic.  Below 1e-3 the series: its error is its first omitted term
    (x⁴/120 of φ1, x⁴/720 of φ2 = 0.5) plus rounding; above, the closed forms: φ2's numerator
    x + expm1(−x) ≈ x²/2 loses expm1's rounding eps·x, a relative 2 eps/x."""
    from decimal import Decimal, localcontext

    with localcontext() as ctx:
        ctx.prec = 50
        X = Decimal(x)
        e = (-X).exp()
        phi1_ref, phi2_ref = float((1 - e) / X), float((X - 1 + e) / (X * X))
    phi1, phi2 = fr.phi(x)
    eps = np.finfo(float).eps
    series = x < 1e-3
    assert abs(phi1 / phi1_ref - 1) <= (x ** 4 / 120 if series else 0.0) + 2 * eps
    assert abs(phi2 / phi2_ref - 1) <= (x ** 4 / 360 if series else 2 * eps / x) + 2 * eps


def test_parameters_cannot_change_after_validation():
    """LuGre is validated once, at construction: an attribute set later would skip the checks
    (e.g. Fs below Fc), so the dataclass is frozen."""
    import dataclasses

    model = fr.LuGre(**PAPER)
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.Fs = 0.5


def test_the_stribeck_curve_is_3_read_from_the_friction_array():
    """``stribeck(f, ω)`` is G(ω) = Fc + (Fs − Fc) exp(−(ω/ωs)²) of (3), written here again, with
    six distinct parameters and a bristle state in the array that G must not read: Fs at rest,
    even in ω, Fc + (Fs − Fc)/e at ±ωs, Fc far beyond.  Catches a Stribeck binding that drops
    the speed or passes another argument, and a kernel that swaps Fc and Fs or ωs for another
    parameter."""
    model = fr.LuGre(Fc=0.05, Fs=0.08, omega_s=0.125, sigma0=120.0, sigma1=0.3, sigma2=2e-4)
    f = fr.new_lugre(model, z0=7e-4)
    for omega in (0.0, 0.125, -0.125, 0.03, -0.4, 2.0, 50.0):
        g = model.Fc + (model.Fs - model.Fc) * math.exp(-(omega / model.omega_s) ** 2)
        assert fr.stribeck(f, omega) == pytest.approx(g, rel=1e-14), omega
    assert fr.stribeck(f, 0.0) == model.Fs and fr.stribeck(f, 50.0) == model.Fc
    assert fr.stribeck(f, 0.125) == pytest.approx(model.Fc + (model.Fs - model.Fc) / math.e, rel=1e-14)
    assert fr.stribeck(f, -0.4) == fr.stribeck(f, 0.4)
    assert f[fr.F_Z] == 7e-4                                   # G reads the array, never writes it


@pytest.mark.parametrize("field", ["sigma1", "sigma2"])
def test_a_damping_of_exactly_zero_is_accepted_and_the_next_number_below_it_refused(field):
    """σ1, σ2 >= 0 (the docstring): 0 itself is a LuGre model without that damping.  Catches the
    bound made strict (0 refused) or loose the other way (the smallest negative accepted)."""
    assert getattr(fr.LuGre(**{**PAPER, field: 0.0}), field) == 0.0
    below = -math.ulp(0.0)
    with pytest.raises(ValueError, match=f"{field}.* = {below!r} must be >= 0$"):
        fr.LuGre(**{**PAPER, field: below})


def test_a_break_away_torque_of_zero_is_refused_as_below_the_coulomb_torque_and_equal_to_it_accepted():
    """Fs >= Fc is the only bound on Fs: Fs = 0 is refused for being below Fc (not as a negative
    number), Fs = Fc (no Stribeck dip) is accepted, the next number below Fc refused."""
    with pytest.raises(ValueError, match=r"^LuGre friction: the break-away torque Fs \(mu_s\) = 0.0 must be >= "
                                         r"the Coulomb torque Fc \(mu\) = 1.0$"):
        fr.LuGre(**{**PAPER, "Fs": 0.0})
    assert fr.LuGre(**{**PAPER, "Fs": PAPER["Fc"]}).Fs == PAPER["Fc"]
    with pytest.raises(ValueError, match="must be >= the Coulomb torque"):
        fr.LuGre(**{**PAPER, "Fs": math.nextafter(PAPER["Fc"], 0.0)})
