"""Discrete current controller of appendix C, designed by pole placement.

Design model: the motor current transfer function (B.10)::

    G_I(s) = (J s + b) / ((L s + R)(J s + b) + kt ke)

discretised with a zero-order hold at T (C.3): G_I(z) = N(z)/D(z), N of
degree 1, D monic of degree 2. The controller (C.5)::

    K(z) = (alpha z^2 + beta z + gamma) / ((z - 1)(z - delta))

places the four closed-loop poles, the roots of (C.8)::

    P(z) = (z - 1)(z - delta) D(z) + (alpha z^2 + beta z + gamma) N(z),

at the requested ones (thesis 7.2.10: z = 0, 0.6, 0.7) plus the plant's
discrete zero. Since P is linear in (alpha, beta, gamma, delta) this is a
4x4 linear (Diophantine) system, built here from polynomial products
(C.11-C.12) and solved numerically; the hand-expanded solution (C.13) is not
used (it has typos, e.g. a coefficient c4 that does not exist). The fourth
pole on the plant zero makes delta equal that zero: K cancels it, and the
reference-to-current response is third order (poles 0, 0.6, 0.7).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import kernels
from motor import _checks, kernel

#: Closed-loop poles chosen in the thesis (section 7.2.10); the fourth is the plant zero.
THESIS_POLES = (0.0, 0.6, 0.7)

#: Sample time of the thesis current controller [s].
THESIS_T = 1e-3


def current_transfer_function(params):
    """Continuous current transfer function I(s)/U(s) of (B.10).

    Parameters
    ----------
    params : motor.presets.MotorParams
        Uses R, L, kt, ke, b and J_rotor (unloaded motor, mu = 0 as in B.6).

    Returns
    -------
    control.TransferFunction
    """
    import control   # here, not at import: it takes 1-2 s (an FMU's start, issue 27)

    p = params
    den = np.polyadd(np.polymul([p.L, p.R], [p.J_rotor, p.b]), [p.kt * p.ke])
    return control.tf([p.J_rotor, p.b], den)


@dataclass(frozen=True)
class CurrentControllerDesign:
    """Result of :func:`design_current_controller`.

    Attributes
    ----------
    alpha, beta, gamma, delta : float
        Coefficients of K(z) (C.5).
    T : float
        Sample time [s].
    plant : control.TransferFunction or None
        ZOH discretisation G_I(z) of (B.10) (C.3); None in a design loaded from an FMU's
        resources (:data:`PRECOMPUTED`).
    controller : control.TransferFunction or None
        K(z); None likewise.
    desired_poles : numpy.ndarray
        The four placed poles (requested ones and the plant zero).
    closed_loop_poles : numpy.ndarray
        Poles of feedback(K G_I, 1) computed by python-control.
    """

    alpha: float
    beta: float
    gamma: float
    delta: float
    T: float
    plant: control.TransferFunction
    controller: control.TransferFunction
    desired_poles: np.ndarray
    closed_loop_poles: np.ndarray


def _tf_coefficients(sys):
    """Numerator and monic denominator coefficient arrays of a SISO transfer function."""
    num = np.trim_zeros(np.atleast_1d(np.squeeze(sys.num[0][0])).astype(float), "f")
    den = np.atleast_1d(np.squeeze(sys.den[0][0])).astype(float)
    return num / den[0], den / den[0]


def solve_pole_placement(num, den, desired):
    """Solve P(z) = prod(z - p) for the coefficients of K(z) (C.8-C.12).

    Parameters
    ----------
    num : array_like
        Plant numerator N(z), degree 1 (highest power first).
    den : array_like
        Plant denominator D(z), monic, degree 2.
    desired : array_like
        Monic desired characteristic polynomial, degree 4.

    Returns
    -------
    numpy.ndarray
        (alpha, beta, gamma, delta).
    """
    def poly5(c):
        return np.pad(c, (5 - len(c), 0))

    # P = (z^2 - z) D + delta (1 - z) D + alpha z^2 N + beta z N + gamma N
    columns = [np.polymul(num, [1, 0, 0]), np.polymul(num, [1, 0]),
               np.asarray(num, float), np.polymul([-1, 1], den)]
    M = np.column_stack([poly5(c) for c in columns])
    rhs = poly5(np.asarray(desired, float)) - poly5(np.polymul([1, -1, 0], den))
    # Row 0 (z^4) reads 1 = 1 for any coefficients; the other four rows are (C.12).
    return np.linalg.solve(M[1:], rhs[1:])


def design_current_controller(params, T=THESIS_T, poles=THESIS_POLES):
    """Design K(z) of (C.5) by pole placement on the ZOH model of G_I(s).

    Parameters
    ----------
    params : motor.presets.MotorParams
        Motor parameters; L must be > 0 (otherwise G_I is not strictly proper).
    T : float
        Sample time [s].
    poles : sequence of 3 float
        Requested closed-loop poles; the fourth is placed on the plant zero.

    Returns
    -------
    CurrentControllerDesign

    Raises
    ------
    ValueError
        For L = 0, non-positive T, or not exactly three finite poles inside
        the unit circle.
    RuntimeError
        If python-control's closed-loop poles differ from the placed ones.
    """
    T = _checks.positive("T", T)
    if params.L == 0.0:
        raise ValueError("current controller design needs L > 0, got L=0.0")
    poles = [_checks.finite(f"poles[{k}]", p) for k, p in enumerate(poles)]
    if len(poles) != 3 or any(abs(p) >= 1.0 for p in poles):
        raise ValueError(f"poles must be three values with |z| < 1, got {poles!r}")
    key = design_key(params, T, poles)
    if key in PRECOMPUTED:
        return PRECOMPUTED[key]
    import control   # here, not at import: it takes 1-2 s (an FMU's start, issue 27)

    plant = control.c2d(current_transfer_function(params), T, "zoh")
    num, den = _tf_coefficients(plant)
    if len(num) != 2 or len(den) != 3:
        raise ValueError(f"expected a ZOH model (a z + b)/(z^2 + c z + d), got num={num}, den={den}")
    plant_zero = -num[1] / num[0]
    desired = np.array([*poles, plant_zero])
    # Plain floats: numpy scalars cost ~0.8 µs a step in the controller's hot path.
    alpha, beta, gamma, delta = (float(c) for c in solve_pole_placement(num, den, np.poly(desired)))
    controller = control.tf([alpha, beta, gamma], np.polymul([1, -1], [1, -delta]), T)
    cl_poles = control.poles(control.feedback(controller * plant, 1))
    # Compare characteristic polynomials: robust to root ordering.
    if not np.allclose(np.poly(cl_poles).real, np.poly(desired), rtol=0, atol=1e-9):
        raise RuntimeError(f"pole placement failed: closed-loop poles {cl_poles}, wanted {desired}")
    design = CurrentControllerDesign(alpha, beta, gamma, delta, T, plant, controller, desired, cl_poles)
    if RECORDING:
        PRECOMPUTED[key] = design
    return design


#: Designs computed ahead, :func:`design_key` -> :class:`CurrentControllerDesign` (without
#: ``plant`` and ``controller``): an FMU's, computed when it was built for its parameters then
#: and loaded from its resources (:mod:`fmus.slave.designs`), so that starting it needs no
#: python-control.  While an FMU is built (``RECORDING``), each design computed is added.
PRECOMPUTED = {}
RECORDING = False


def design_key(params, T, poles) -> tuple:
    """What :func:`design_current_controller` depends on, as plain numbers."""
    p = params
    return ("current_controller", *(float(v) for v in (p.R, p.L, p.kt, p.ke, p.b, p.J_rotor, T)),
            *(float(v) for v in poles))


class CurrentController:
    """Runtime K(z) with voltage saturation and anti-windup.

    Anti-windup: the Astrom-Wittenmark polynomial form with observer
    polynomial A_aw(z) = z^2 (Computer-Controlled Systems, ch. 9), i.e.
    K(z) run as the difference equation::

        v_k = (1 + delta) u_{k-1} - delta u_{k-2} + alpha e_k + beta e_{k-1} + gamma e_{k-2}
        u_k = sat(v_k, +-v_max)

    with the *saturated* past outputs u in the recursion. While unsaturated
    it is exactly K(z); while saturated the integrator state is the actual
    voltage, so nothing winds up and the loop leaves saturation without
    overshoot due to stored integral action.

    Parameters
    ----------
    design : CurrentControllerDesign
        Controller coefficients.
    v_max : float
        Saturation voltage [V], > 0.
    """

    def __init__(self, design, v_max):
        self.design = design
        self.v_max = _checks.positive("v_max", v_max)
        # Coefficients and state in one array, the C struct pc_controller (kernels/src/drive.h).
        self.buf = np.zeros(kernels.size(kernel.CONTROLLER))
        for name in ("alpha", "beta", "gamma", "delta"):
            self.buf[kernel.CONTROLLER[name]] = getattr(design, name)
        self.buf[kernel.CONTROLLER["v_max"]] = self.v_max
        self._update = kernel.Controller(self.buf).update
        self.reset()

    @staticmethod
    def idle_buffer(v_max):
        """A controller buffer with zero coefficients: the voltage-mode drive's (never sampled)."""
        b = np.zeros(kernels.size(kernel.CONTROLLER))
        b[kernel.CONTROLLER["v_max"]] = v_max
        return b

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k != "_update"}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._update = kernel.Controller(self.buf).update

    def reset(self, v0=0.0):
        """Restart from a steady voltage ``v0`` with zero error (bumpless start)."""
        v0 = min(max(_checks.finite("v0", v0), -self.v_max), self.v_max)
        c, b = kernel.CONTROLLER, self.buf
        b[c["u1"]] = b[c["u2"]] = v0
        b[c["e1"]] = b[c["e2"]] = 0.0

    def update(self, i_ref, i_meas):
        """One controller sample: voltage to hold over the next period.

        Parameters
        ----------
        i_ref : float
            Current reference at the sample instant [A].
        i_meas : float
            Measured or observed current at the sample instant [A].

        Returns
        -------
        float
            Saturated voltage [V].
        """
        return self._update(float(i_ref), float(i_meas))
