"""One-step integrators for y' = f(y) over a communication step.

Inputs are held over a communication step (zero-order hold), so within a
step the right-hand side is autonomous and smooth: fixed-step RK4 and an
embedded Dormand-Prince 5(4) pair with error control are all we need.
"""
from __future__ import annotations

import numpy as np


class IntegrationError(RuntimeError):
    """The integrator could not meet its tolerance or produced non-finite values."""


class WorkLimitError(IntegrationError):
    """An adaptive integration would need more right-hand-side evaluations than allowed.

    Attributes
    ----------
    evaluations : int
        Evaluations done when it stopped (the next step attempt would have exceeded the limit).
    limit : int
        The evaluations allowed.
    reached : float
        How far into the step the accepted internal steps got [s].
    """

    def __init__(self, evaluations: int, limit: int, reached: float):
        self.evaluations, self.limit, self.reached = evaluations, limit, reached
        super().__init__(f"{evaluations} right-hand-side evaluations reached t+{reached:.3g} s; the next internal "
                         f"step would exceed the {limit} allowed")


def rk4(f, y, dt: float, substeps: int = 1):
    """Classical fourth-order Runge-Kutta with ``substeps`` equal steps over dt."""
    h = dt / substeps
    for _ in range(substeps):
        k1 = f(y)
        k2 = f(y + 0.5 * h * k1)
        k3 = f(y + 0.5 * h * k2)
        k4 = f(y + h * k3)
        y = y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return y


# Dormand-Prince 5(4) tableau (Hairer, Norsett, Wanner, Solving ODE I, table 5.2).
_DP_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_DP_A = (
    (),
    (1 / 5,),
    (3 / 40, 9 / 40),
    (44 / 45, -56 / 15, 32 / 9),
    (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
    (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656),
    (35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84),
)
_DP_B5 = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0])
_DP_B4 = np.array([5179 / 57600, 0.0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40])
_DP_ERR = _DP_B5 - _DP_B4


def dopri5(f, y, dt: float, rtol: float, atol: float, h_start: float | None = None, max_steps: int = 100000,
           max_evaluations: int | None = None):
    """Adaptive Dormand-Prince 5(4) over exactly dt.

    ``max_evaluations`` bounds the calls of ``f`` (None: unbounded): a step attempt (6 calls)
    that would exceed it is not begun, :class:`WorkLimitError` is raised instead; ``y`` is
    never modified, so the caller keeps its state.

    Returns
    -------
    y : ndarray
        The state at the end of the step.
    h_next : float
        The step-size suggestion for the next call (warm start).
    n_steps : int
        Accepted internal steps.
    n_evaluations : int
        Calls of ``f``.
    """
    t = 0.0
    h = min(dt, h_start) if h_start else dt
    if max_evaluations is not None and max_evaluations < 7:    # not even one step attempt
        raise WorkLimitError(0, max_evaluations, 0.0)
    k = np.empty((7, y.size))
    k[0] = f(y)
    n_accepted, n_evaluations = 0, 1
    for _ in range(max_steps):
        if max_evaluations is not None and n_evaluations + 6 > max_evaluations:
            raise WorkLimitError(n_evaluations, max_evaluations, t)
        n_evaluations += 6
        last = t + h >= dt * (1.0 - 1e-12)
        if last:
            h = dt - t
        for s in range(1, 7):
            ys = y + h * np.dot(_DP_A[s], k[:s])
            k[s] = f(ys)
        y_new = ys  # stage 7 is evaluated at the 5th-order solution (FSAL)
        err_vec = h * (_DP_ERR @ k)
        scale = atol + rtol * np.maximum(np.abs(y), np.abs(y_new))
        err = float(np.sqrt(np.mean((err_vec / scale) ** 2)))
        if not np.isfinite(err):
            raise IntegrationError(f"non-finite state at t+{t:.3g} s within the step")
        if err <= 1.0:
            t += h
            y = y_new
            k[0] = k[6]
            n_accepted += 1
            factor = 5.0 if err == 0.0 else min(5.0, 0.9 * err ** -0.2)
            if last:
                return y, max(h * factor, 1e-12), n_accepted, n_evaluations
            h *= factor
        else:
            h *= max(0.2, 0.9 * err ** -0.2)
        if h < 1e-14 * dt:
            raise IntegrationError(f"step size underflow ({h:.3g} s) at t+{t:.3g} s within the step: the "
                                   f"tolerances rtol = {rtol!r}, atol = {atol!r} cannot be met")
    raise IntegrationError(f"more than {max_steps} internal steps in one communication step")
