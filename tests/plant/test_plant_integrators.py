"""The plant's one-step integrators (plant/integrators.py) against the exact solution of a linear
system, expm(A t) y0 (scipy, no code shared): their orders, the embedded pair's step control and
the work limit."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from plant.integrators import IntegrationError, WorkLimitError, dopri5, rk4

#: A damped oscillator (25 rad^2/s^2, 0.4 1/s) and a slow mode: y' = A y.
A = np.array([[0.0, 1.0, 0.0], [-25.0, -0.4, 0.0], [0.0, 0.3, -2.0]])
Y0 = np.array([1.0, -0.5, 0.25])


def f(y):
    return A @ y


def exact(t):
    return expm(A * t) @ Y0


def test_rk4_is_fourth_order_and_its_substeps_are_equal_steps():
    """Catches a wrong RK4 weight or stage (the global error would not fall 16 times when the
    step halves) and substeps that are not equal steps over dt."""
    dt = 0.4
    errors = [np.max(np.abs(rk4(f, Y0, dt, n) - exact(dt))) for n in (16, 32, 64)]
    for coarse, fine in zip(errors, errors[1:]):
        assert 14.0 < coarse / fine < 18.0, errors
    assert np.array_equal(rk4(f, Y0, dt, 2), rk4(f, rk4(f, Y0, dt / 2), dt / 2))


def test_one_dopri5_step_is_fifth_order():
    """One step (tolerances that accept anything, h_start = dt): its local error falls about 64
    times when dt halves.  Catches a wrong Dormand-Prince coefficient in the stages or in the
    fifth-order (FSAL) row, which leave a lower order."""
    local = []
    for dt in (0.1, 0.05, 0.025):
        y, h_next, steps, evaluations = dopri5(f, Y0.copy(), dt, rtol=1e3, atol=1e3, h_start=dt)
        assert (steps, evaluations) == (1, 7) and h_next == 5.0 * dt
        local.append(np.max(np.abs(y - exact(dt))))
    for coarse, fine in zip(local, local[1:]):
        assert 50.0 < coarse / fine < 75.0, local


@pytest.mark.parametrize("rtol", [1e-6, 1e-10])
def test_dopri5_meets_its_tolerance_over_a_long_step_and_leaves_y_alone(rtol):
    """Catches an error estimate that does not control the step (the result off by more than a
    few tolerances), a step that does not end exactly at dt, or a y modified in place."""
    y0 = Y0.copy()
    dt = 2.0
    y, h_next, steps, evaluations = dopri5(f, y0, dt, rtol=rtol, atol=rtol * 1e-3)
    assert np.array_equal(y0, Y0)
    assert np.max(np.abs(y - exact(dt))) < 50 * rtol * np.max(np.abs(Y0))
    assert steps > 3 and evaluations >= 1 + 6 * steps and 0.0 < h_next <= 5.0 * dt
    tighter = dopri5(f, Y0, dt, rtol=rtol / 100, atol=rtol * 1e-5)
    assert tighter[2] > steps                                  # a tighter tolerance takes more steps


def test_the_work_limit_stops_before_an_attempt_that_would_pass_it():
    """Catches a limit that is checked after the attempt (more evaluations than allowed), or a
    WorkLimitError whose evaluations, limit or time reached are not those of the stop."""
    with pytest.raises(WorkLimitError) as caught:
        dopri5(f, Y0, 1.0, rtol=1e-3, atol=1e-6, max_evaluations=6)
    assert (caught.value.evaluations, caught.value.limit, caught.value.reached) == (0, 6, 0.0)
    calls = []

    def counted(y):
        calls.append(1)
        return f(y)

    free = dopri5(counted, Y0, 2.0, rtol=1e-10, atol=1e-13)
    limit = free[3] - 6                                          # one attempt short
    calls.clear()
    with pytest.raises(WorkLimitError) as caught:
        dopri5(counted, Y0, 2.0, rtol=1e-10, atol=1e-13, max_evaluations=limit)
    assert caught.value.evaluations == len(calls) <= limit and caught.value.limit == limit
    assert 0.0 < caught.value.reached < 2.0
    assert f"{caught.value.evaluations} right-hand-side evaluations reached t+" in str(caught.value)


def test_a_non_finite_derivative_is_refused_naming_where():
    """Catches an integrator that returns a NaN state instead of refusing it (y' = y, whose
    derivative is NaN once y passes 1.2, from y = 1 over 0.5 s)."""
    with pytest.raises(IntegrationError, match=r"^non-finite state at t\+0 s within the step$"):
        dopri5(lambda y: y if y[0] < 1.2 else y * math.nan, np.array([1.0]), 0.5, rtol=1e-6, atol=1e-9)


def test_the_rk4_stability_limit_is_where_one_step_of_a_decay_stops_shrinking():
    """RK4 on y' = -y/tau over h multiplies y by R(-h/tau) = 1 - x + x^2/2 - x^3/6 + x^4/24
    (x = h/tau); the plant's limit (simulator.RK4_REAL_STABILITY, used for the Baumgarte term
    and the in-plant drives' armature circuits) is the x > 0 where R = 1 again, the real root
    of x^3/24 - x^2/6 + x/2 - 1.  Catches a limit that is
    not that root (a step refused that is stable, or one accepted that diverges)."""
    from plant.simulator import RK4_REAL_STABILITY as limit
    root = min(r.real for r in np.roots([1 / 24, -1 / 6, 1 / 2, -1.0]) if abs(r.imag) < 1e-12)
    assert limit == pytest.approx(root, rel=1e-13)
    for x, shrinks in ((limit * (1 - 1e-9), True), (limit * (1 + 1e-9), False)):
        factor = rk4(lambda y: -y, np.array([1.0]), x)[0]
        assert (abs(factor) < 1.0) == shrinks, (x, factor)


def test_a_step_whose_error_is_exactly_the_tolerance_is_accepted_and_shrinks_the_next_by_0_9():
    """Hairer's criterion (Solving ODE I, II.4): an attempt is accepted when its error norm is
    <= 1, and the next step is h * min(5, 0.9 err^-1/5).  On y' = -3 y over one attempt, with
    rtol = 0 and atol set to the attempt's error estimate |h (b5 - b4) . k| (the stages recorded,
    the Dormand-Prince weights of table 5.2 written here), the norm is exactly 1: accepted in
    7 evaluations with the next step 0.9 h; one ulp less tolerance is a rejection.  Catches an
    acceptance test with ``<`` for ``<=`` and a step-size factor or safety other than Hairer's."""
    b5 = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0])
    b4 = np.array([5179 / 57600, 0.0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40])
    stages = []

    def decay(y):
        stages.append(-3.0 * y)
        return stages[-1]

    h, y0 = 0.25, np.array([1.0])
    dopri5(decay, y0, h, 0.0, 1.0)                    # a loose tolerance: one attempt, its 7 stages
    assert len(stages) == 7
    tolerance = abs(float(h * ((b5 - b4) @ np.array(stages))[0]))
    assert tolerance > 0.0
    y, h_next, steps, evaluations = dopri5(decay, y0, h, 0.0, tolerance)
    assert (steps, evaluations, h_next) == (1, 7, 0.9 * h)
    assert y[0] == pytest.approx(math.exp(-3.0 * h), rel=10 * tolerance)
    _, _, steps, evaluations = dopri5(decay, y0, h, 0.0, math.nextafter(tolerance, 0.0))
    assert steps > 1 and evaluations > 7


@pytest.mark.parametrize("h_start", [0.0, 0.5, 1.0, 4.0, math.inf, math.nan])
def test_a_warm_start_only_caps_the_first_trial_step(h_start):
    """h_start caps the first trial step at min(dt, h_start): one not below dt (or 0, or one that
    is no step at all, NaN: no cap either) gives exactly the run without it, a smaller one starts
    smaller and still meets the tolerance at dt.  Catches a cap taken the other way round (NaN,
    which compares false, would become the first step) or a warm start ignored."""
    dt, rtol = 1.0, 1e-8
    cold = dopri5(f, Y0, dt, rtol=rtol, atol=1e-11)
    warm = dopri5(f, Y0, dt, rtol=rtol, atol=1e-11, h_start=h_start)
    if h_start == 0.5:
        first = dopri5(f, Y0, 0.5, rtol=1e3, atol=1e3, h_start=0.5)[0]   # the capped first step alone
        assert np.array_equal(dopri5(f, Y0, dt, rtol=1e3, atol=1e3, h_start=0.5)[0],
                              dopri5(f, first, 0.5, rtol=1e3, atol=1e3, h_start=0.5)[0])
        assert np.max(np.abs(warm[0] - exact(dt))) < 50 * rtol
    else:
        assert np.array_equal(warm[0], cold[0]) and warm[1:] == cold[1:]
