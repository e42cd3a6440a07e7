"""The current controller's design in C (kernels/src/design.c: the native FMUs' drives design
with it for motor values they carry no python-control design of) against independent oracles:
python-control's ``c2d`` (scipy's Padé expm of another realisation) for the ZOH model, the
model and the design solved again in 50-digit arithmetic (mpmath: its own expm and the 4x4
Diophantine solve of appendix C), python-control's design (motor.current_controller) within
its own error, and the closed loop's poles through python-control.

design.c computes in double-double (106 bits) and rounds once, so each ZOH and design value is
held to one rounding: :func:`rounding_tolerance`."""
import ctypes
from dataclasses import replace

import mpmath
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

import kernels
from motor import current_controller as cc
from motor.presets import MOTOR_PRESETS

_p, _d = ctypes.c_void_p, ctypes.c_double
_zoh = kernels.function("pc_current_zoh", None, _p, _d, _p, _p)
_design = kernels.function("pc_current_design", ctypes.c_int, _p, _d, _p, _p, _p)
NO_L, NOT_ZOH, ZERO_AT_ONE = 1, 2, 4


def motor_row(p):
    return np.array([p.R, p.L, p.kt, p.ke, p.b, p.J_rotor], dtype=np.float64)


def c_zoh(p, T):
    m, num, den = motor_row(p), np.zeros(2), np.zeros(3)
    _zoh(m.ctypes.data, T, num.ctypes.data, den.ctypes.data)
    return num, den


def c_design(p, T, poles=cc.THESIS_POLES):
    m, out, detail = motor_row(p), np.zeros(4), _d()
    code = _design(m.ctypes.data, T, np.array(poles, dtype=np.float64).ctypes.data, out.ctypes.data,
                   ctypes.byref(detail))
    return code, out, detail.value


def augmented_entries(p, T):
    """The augmented matrix's five entries (A T and B T, design.c's inputs to its expm) in 60 digits."""
    with mpmath.workdps(60):
        R, L, kt, ke, b, J, T = (mpmath.mpf(float(v)) for v in (*motor_row(p), T))
        return [-R / L * T, -ke / L * T, T / L, kt / J * T, -b / J * T]


def exact_model(entries, digits=50):
    """(num, den) of the ZOH model of the augmented matrix [[m11, m12, m13], [m21, m22, 0], 0] in
    `digits` digits: the input's column of mpmath's expm of it, Ad as e^sigma expm(M - sigma I)
    (sigma half the trace: a decayed Ad, e^-171 at R T / L = 340, keeps its own 50 digits, where
    expm(M) holds it only to 1e-50 of its norm) and det(Ad) = e^trace."""
    with mpmath.workdps(digits):
        m11, m12, m13, m21, m22 = entries
        F = mpmath.expm(mpmath.matrix([[m11, m12, m13], [m21, m22, 0], [0, 0, 0]]))
        sigma = (m11 + m22) / 2
        E = mpmath.exp(sigma) * mpmath.expm(mpmath.matrix([[m11 - sigma, m12], [m21, m22 - sigma]]))
        num = (F[0, 2], E[0, 1] * F[1, 2] - E[1, 1] * F[0, 2])
        return num, (1, -(E[0, 0] + E[1, 1]), mpmath.exp(m11 + m22))


def exact_zoh(p, T, digits=50):
    """(num, den) of the motor's ZOH model in `digits` digits."""
    return exact_model(augmented_entries(p, T), digits)


def exact_placement(num, den, poles=cc.THESIS_POLES, digits=50, exact=False):
    """Appendix C's 4x4 system (C.12) for the model (num, den), solved by LU in `digits` digits
    with np.poly's convolution of the four poles: no formula shared with design.c's.  Doubles,
    or with `exact` mpmath's numbers."""
    with mpmath.workdps(digits):
        (n1, n0), (_, d1, d0) = [mpmath.mpf(v) for v in num], [mpmath.mpf(v) for v in den]
        want = [mpmath.mpf(1), 0, 0, 0, 0]
        for r in [mpmath.mpf(x) for x in poles] + [-n0 / n1]:
            want = [want[0]] + [want[j] - r * want[j - 1] for j in range(1, 5)]
        M = mpmath.matrix([[n1, 0, 0, -1], [n0, n1, 0, 1 - d1], [0, n0, n1, d1 - d0], [0, 0, n0, d0]])
        rhs = mpmath.matrix([want[1] - (d1 - 1), want[2] - (d0 - d1), want[3] + d0, want[4]])
        solution = list(mpmath.lu_solve(M, rhs))
        return solution if exact else np.array([float(v) for v in solution])


def exact_design(p, T):
    """Appendix C for the motor in 50 digits: the exact ZOH model, then the exact placement."""
    with mpmath.workdps(50):
        return exact_placement(*exact_zoh(p, T))


#: What python-control's scaling and squaring (scipy's expm in double) leaves of the ZOH model,
#: relative: each squaring can double the rounding, and the stiffest motors drawn (R T / L up to
#: 2e4, kt T / J up to 5e3) take up to 16 of them: 2^16 eps is 1.5e-11.
ZOH_RELATIVE = 3e-11


def zoh_tolerance(p, T, num):
    """What python-control's rounding leaves of the ZOH numerator: :data:`ZOH_RELATIVE` of it, or
    1e-15 of T / L (the input's integral before the armature's decay: a strongly damped or
    oscillating motor leaves a numerator far below it, and a double expm loses that much of it)."""
    return ZOH_RELATIVE * np.abs(num).max() + 1e-15 * T / p.L


def condition_numbers(values, entries, h=mpmath.mpf(10) ** -25):
    """Each of values(entries)'s relative condition number: sum over the five entries of
    |m d(value)/dm| / |value| (central differences at 1e-25 in 60 digits), what a relative change
    of each entry by one unit does to that value."""
    with mpmath.workdps(60):
        at = [mpmath.mpf(v) for v in values(entries)]
        total = [mpmath.mpf(0)] * len(at)
        for k in range(len(entries)):
            up, down = list(entries), list(entries)
            up[k], down[k] = up[k] * (1 + h), down[k] * (1 - h)
            total = [t + abs((u - d) / (2 * h)) for t, u, d in zip(total, values(up), values(down))]
        return np.array([float(t / abs(a)) if a != 0 else np.inf for t, a in zip(total, at)])


EPS = np.finfo(float).eps


def rounding_tolerance(exact, kappa):
    """One rounding: design.c's double-double value rounded once to double (half an ulp, at most
    eps / 2 of it), plus what its 106 bits leave: 2^-104 per operation, doubled at most 16 times
    by its expm's squarings (the block's norm below 2^15 over the range) and amplified by the
    value's condition number kappa, 2^-88 kappa = eps 2^-36 kappa per operation.  Taken as
    eps |exact| (1 + 2^-30 kappa): twice the rounding, 64 operations' worth of the rest (kappa
    stays below 1e5 over the range, so this is one ulp).  Values below the smallest normal double
    are held to it absolutely (subnormals carry fewer digits)."""
    return EPS * np.abs(exact) * (1.0 + 2.0 ** -30 * kappa) + np.finfo(float).tiny


def assert_within(names, got, exact, tolerance):
    """Each value within its own tolerance, the message naming the value, its error and bound."""
    error = np.abs(np.asarray(got) - exact)
    bad = [f"{n}: {g!r} vs {e!r} (error {d:.3g} > {t:.3g})"
           for n, g, e, d, t in zip(names, got, exact, error, tolerance) if not d <= t]
    assert not bad, "; ".join(bad)


def zoh_values(entries):
    """n1, n0, d1, d0 of :func:`exact_model` (mpmath numbers)."""
    (n1, n0), (_, d1, d0) = exact_model(entries)
    return [n1, n0, d1, d0]


def design_values(entries):
    """alpha, beta, gamma, delta of appendix C for :func:`exact_model` (mpmath numbers), the LU
    solve in 50 digits more than the decades d0 = e^trace lies below 1 (LU holds a solution to
    its digits of the largest: gamma and delta scale with d0 and n0, e^-700 at R T / L = 700)."""
    (n1, n0), (_, d1, d0) = exact_model(entries)
    decades = int(mpmath.ceil(max(0, -(entries[0] + entries[4])) / mpmath.log(10)))
    return exact_placement((n1, n0), (1, d1, d0), digits=50 + decades, exact=True)


def python_control_design(p, T):
    cc.PRECOMPUTED.clear()   # designed now by python-control, not loaded
    d = cc.design_current_controller(p, T)
    return d, np.array([d.alpha, d.beta, d.gamma, d.delta])


def drawn_motor(R, L, k, b, J):
    """motor1 with the drawn values (kt = ke = k)."""
    return replace(MOTOR_PRESETS["motor1"], R=R, L=L, kt=k, ke=k, b=b, J_rotor=J)


motors = st.builds(drawn_motor, st.floats(0.1, 20.0), st.floats(1e-5, 2e-2), st.floats(5e-3, 0.5),
                   st.floats(1e-7, 2e-3), st.floats(1e-6, 2e-3))
periods = st.sampled_from([1e-4, 2.5e-4, 5e-4, 1e-3, 2e-3, 1e-2])
PRESETS = [(name, T) for name in sorted(MOTOR_PRESETS) if MOTOR_PRESETS[name].L > 0.0 for T in (2.5e-4, 1e-3, 1e-2)]

#: Stiff and nearly undamped motors where design.c's double expm (scaling and squaring of exp
#: itself, before s38) was furthest from the exact model, relative: the random draw of s37
#: (numerator 2e-9 off, 5000 eps times its condition number; a slow mode e^-7 squared from
#: e^(-7 / 2^12), its rounding doubled by each squaring) and the worst of 900 draws over the range
#: (numerator 5e-10: R T / L = 680, b T / J = 4e-4; denominator 6e-12: R T / L = 2e4; delta 3e-11).
STIFF = [(drawn_motor(11.412320631517575, 0.007794717009052486, 0.15352563211481132, 1e-7, 1e-6), 1e-2),
         (drawn_motor(3.3873828575664024, 1e-5, 0.5, 2.0180165665577706e-07, 1e-6), 2e-3),
         (drawn_motor(20.0, 1e-5, 0.05202751534851133, 0.00019906570495682773, 2e-3), 1e-2),
         (drawn_motor(20.0, 1e-5, 0.5, 1e-7, 1e-6), 5e-4)]


def stiff_examples(test):
    for p, T in STIFF:
        test = example(p, T)(test)
    return test


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(motors, periods)
def test_zoh_model_is_python_controls_c2d(p, T):
    """Catches a wrong augmented matrix (B, the sign of ke or b), a truncated series or missing
    squarings, a numerator or denominator of the adjugate misread: python-control's c2d of the
    transfer function (B.10) within python-control's own rounding (:func:`zoh_tolerance` for the
    numerator, :data:`ZOH_RELATIVE` for the monic denominator)."""
    import control

    num, den = c_zoh(p, T)
    ref_num, ref_den = cc._tf_coefficients(control.c2d(cc.current_transfer_function(p), T, "zoh"))
    assert den[0] == 1.0
    np.testing.assert_allclose(num, ref_num, rtol=0, atol=zoh_tolerance(p, T, ref_num))
    np.testing.assert_allclose(den, ref_den, rtol=0, atol=ZOH_RELATIVE)


def _assert_the_exact_zoh_model(p, T):
    """design.c's n1, n0, d1, d0 for motor ``p`` at period ``T`` each within
    :func:`rounding_tolerance` of the model in 50 digits, and d2 = 1."""
    num, den = c_zoh(p, T)
    entries = augmented_entries(p, T)
    exact = np.array([float(v) for v in zoh_values(entries)])
    kappa = condition_numbers(zoh_values, entries)
    assert den[0] == 1.0
    assert_within(("n1", "n0", "d1", "d0"), [*num, *den[1:]], exact, rounding_tolerance(exact, kappa))


@stiff_examples
@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(motors, periods)
def test_zoh_model_is_the_exact_one_within_one_rounding(p, T):
    """n1, n0, d1, d0 each within :func:`rounding_tolerance` of the model in 50 digits (about one
    ulp: the condition numbers over the range stay below 1e5).  Catches, beside a wrong model, a
    model computed in double: scaling and squaring exp loses up to 5e5 eps times the condition
    number (:data:`STIFF`, each of which fails in double)."""
    _assert_the_exact_zoh_model(p, T)


@stiff_examples
@settings(max_examples=30, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(motors, periods)
def test_design_is_the_exact_design_within_one_rounding(p, T):
    """alpha, beta, gamma, delta each within :func:`rounding_tolerance` of appendix C in 50
    digits (the exact model, the 4x4 system solved by LU), where that system has one solution.
    Catches a design made from a double model or in double (1e-9 off at :data:`STIFF`'s first),
    beside a wrong design."""
    code, c, _ = c_design(p, T)
    entries = augmented_entries(p, T)
    try:
        exact = np.array([float(v) for v in design_values(entries)])
        kappa = condition_numbers(design_values, entries)
    except ZeroDivisionError:     # mpmath: the 4x4 system singular in 50 digits (no unique placement)
        assume(False)
    assert code == 0
    assert_within(("alpha", "beta", "gamma", "delta"), c, exact, rounding_tolerance(exact, kappa))


@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(motors, periods)
def test_design_is_the_exact_pole_placement_of_its_model(p, T):
    """Catches a coefficient of the wrong polynomial, a pole dropped or doubled, delta not on
    the plant's zero: alpha, beta, gamma, delta within 1e-13 (relative to the largest) of
    appendix C's 4x4 system for the same ZOH model solved in 50 digits, where that system has one
    solution (a motor whose armature pole underflows in T, e.g. R T / L = 1000, leaves it singular:
    such draws are skipped; found by Hypothesis at the s37 merge)."""
    code, c, _ = c_design(p, T)
    assert code == 0
    try:
        exact = exact_placement(*c_zoh(p, T))
    except ZeroDivisionError:     # mpmath: the 4x4 system singular in 50 digits (no unique placement)
        assume(False)
    np.testing.assert_allclose(c, exact, rtol=0, atol=1e-13 * np.abs(exact).max())


@pytest.mark.parametrize("name, T", PRESETS)
def test_design_is_python_controls_within_its_own_error(name, T):
    """The motor presets: python-control's design is the exact one within 4e-10 of its largest
    coefficient (its 4x4 solve is near singular: delta is close to the pole at 1), and design.c's
    within 1e-14; the two within python-control's own error.  Catches the C design drifting from
    the one the pythonfmu twin uses by more than that twin's own rounding."""
    p = MOTOR_PRESETS[name]
    code, c, _ = c_design(p, T)
    _, ref = python_control_design(p, T)
    exact = exact_design(p, T)
    scale = np.abs(exact).max()
    own = np.abs(ref - exact).max()
    assert code == 0 and own <= 4e-10 * scale
    assert np.abs(c - exact).max() <= 1e-14 * scale
    assert np.abs(c - ref).max() <= own + 1e-14 * scale


@settings(max_examples=30, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(motors, periods)
def test_design_places_the_closed_loop_poles_through_python_control(p, T):
    """K(z) of the C coefficients closed around python-control's ZOH model: its poles are the
    thesis' 0, 0.6, 0.7 and the plant's zero (compared as polynomials, as
    design_current_controller checks its own).  Catches a controller that is consistent with
    design.c's own plant but not with the motor."""
    import control

    code, (alpha, beta, gamma, delta), _ = c_design(p, T)
    plant = control.c2d(cc.current_transfer_function(p), T, "zoh")
    num, _ = cc._tf_coefficients(plant)
    assume(abs(num[0]) > 0.0)
    controller = control.tf([alpha, beta, gamma], np.polymul([1, -1], [1, -delta]), T)
    poles = control.poles(control.feedback(controller * plant, 1))
    want = np.poly([*cc.THESIS_POLES, -num[1] / num[0]])
    assert code == 0
    np.testing.assert_allclose(np.poly(poles).real, want, rtol=0, atol=1e-8)


def test_design_refuses_what_design_current_controller_refuses():
    """L = 0 (G_I not strictly proper) is refused with its code, b = 0 (the plant's zero on the
    controller's integrator: no unique K) with its own, and a motor whose ZOH
    numerator underflows to 0 (T far below L's time scale) with NOT_ZOH naming that value;
    the thesis presets at the thesis' T are accepted.  Catches a design returning NaN or inf
    coefficients with success."""
    p = MOTOR_PRESETS["motor1"]
    assert c_design(replace(p, L=0.0), 1e-3)[0] == NO_L
    assert c_design(replace(p, b=0.0), 1e-3)[0] == ZERO_AT_ONE
    code, _, detail = c_design(replace(p, L=1e300), 1e-300)
    assert code == NOT_ZOH and detail == 0.0
    for name in ("motor1", "motor2"):
        code, c, _ = c_design(MOTOR_PRESETS[name], cc.THESIS_T)
        assert code == 0 and np.isfinite(c).all()


@pytest.mark.parametrize("coupling", ["ke", "kt"])
@pytest.mark.parametrize("T", [1e-4, 1e-2, 0.1])
def test_zoh_model_is_exact_when_a_coupling_entry_underflows_to_zero(coupling, T):
    """A motor whose back-EMF entry ke T / L (or torque entry kt T / J) underflows to 0 in double
    (ke or kt the smallest positive double: a valid motor) while the other coupling is below,
    near or far above 1: its ZOH model is still the exact one within one rounding.  design.c
    balances the two couplings by a scale 2^p of the speed only when both are non-zero:
    ilogb(0) is FP_ILOGB0, and a scale taken from it sends the other coupling to 0 or to inf
    (a NaN model)."""
    p = replace(MOTOR_PRESETS["motor1"], **{coupling: 5e-324})
    couplings = (p.ke * T / p.L, p.kt * T / p.J_rotor)   # in double, as design.c's
    assert (couplings[0] == 0.0) == (coupling == "ke") and (couplings[1] == 0.0) == (coupling == "kt")
    _assert_the_exact_zoh_model(p, T)


@pytest.mark.parametrize("b", [100.0, 300.0, 3000.0])
def test_zoh_model_is_exact_when_the_mechanical_mode_decays_within_the_step(b):
    """A heavily damped rotor (b T / J from 680 to 2e4, outside the drawn motors' range, the
    mechanical mode decayed to e^-680 .. e^-2e4 within one step) beside a slow armature
    (R T / L = 1.65): the ZOH model is still the exact one within one rounding.  design.c
    computes Ad as e^c exp(M - c I) with c the rightmost eigenvalue's real part; a c off by
    half the damping leaves exp(M - c I) a mode of e^+1000 (inf, a NaN model): caught here, not by
    the drawn motors (b T / J below 20).  Training sample 4561's survivor."""
    p, T = replace(MOTOR_PRESETS["motor1"], b=b), 1e-3
    _assert_the_exact_zoh_model(p, T)
