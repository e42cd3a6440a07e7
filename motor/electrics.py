"""Electrical model of the DC motor and the torque it delivers to the shaft.

Armature circuit (4.162, B.1)::

    L di/dt + R i + ke omega = v

Shaft torque delivered to the mechanism (B.2 with B.3; the rotor inertia
J_rotor is integrated by the plant, 4.139)::

    tau = kt i - b omega - mu sign(omega)

Over one step of length h the voltage v and the speed omega are held
(zero-order hold), so (4.162) is a linear scalar ODE with constant input.
Every integration method is then one affine map::

    i(t + h) = a i(t) + g (v - ke omega)

and only the pair (a, g) differs between methods
(:func:`electrical_step_coefficients`). This is the single discretisation of
the electrical model, used by the drive and by the dynamic current observer.
"""

import ctypes
import functools

import kernels
from motor import _checks, kernel

#: Names accepted by :func:`electrical_step_coefficients`.
ELECTRICAL_METHODS = ("exact", "euler", "quasi_static")


def electrical_step_coefficients(R, L, h, method="exact"):
    """Coefficients (a, g) of ``i(t+h) = a i(t) + g (v - ke omega)`` for held v, omega.

    Parameters
    ----------
    R : float
        Armature resistance [ohm], > 0.
    L : float
        Armature inductance [H], >= 0.
    h : float
        Step length [s], > 0.
    method : {"exact", "euler", "quasi_static"}
        ``"exact"``: analytic solution of (4.162) for held input,
        a = exp(-R h / L), g = (1 - a) / R (computed with ``expm1``, exact to
        rounding for any h/(L/R); with L = 0 it is the quasi-static limit).
        ``"euler"``: explicit Euler, a = 1 - h R / L, g = h / L. Unstable
        (|a| > 1) when h > 2 L / R, e.g. with the thesis motors' L/R ~ 0.6 ms
        it is stable at h = 1 ms (a ~ -0.65, oscillating) but not when L/R is
        100x shorter than the step.
        ``"quasi_static"``: L di/dt neglected (L = 0), a = 0, g = 1 / R, i.e.
        i = (v - ke omega) / R, the same expression as the static observer (7.20).

    Returns
    -------
    tuple of float
        (a, g).

    Raises
    ------
    ValueError
        Non-physical R, L or h, unknown method, or Euler with L = 0.
    """
    R = _checks.positive("R", R)
    L = _checks.non_negative("L", L)
    h = _checks.positive("h", h)
    _checks.choice("method", method, ELECTRICAL_METHODS)
    if method == "euler" and L == 0.0:
        raise ValueError(f"method 'euler' needs L > 0, got L = {L!r}; use 'quasi_static'")
    ag = (ctypes.c_double * 2)()
    _coefficients_kernel("pc_electrical_step_coefficients")(R, L, h, ELECTRICAL_METHODS.index(method), ag)   # kernels/src/electrics.c
    return ag[0], ag[1]


@functools.cache
def _coefficients_kernel(name: str):
    """A kernel of electrics.c with the coefficients' signature ``(R, L, h, method, out[2])``,
    bound once: ``pc_electrical_step_coefficients`` or ``pc_mean_current_coefficients``."""
    return kernels.function(name, ctypes.c_int, ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_int,
                            ctypes.POINTER(ctypes.c_double))


def mean_current_coefficients(R, L, h, method="exact"):
    """Coefficients (w_i, w_u) of the current averaged over a step, ``w_i i(t) + w_u (v - ke omega)``.

    The same held input and method as :func:`electrical_step_coefficients`:
    ``"exact"``: the mean of i(t + s) = u/R + (i(t) - u/R) exp(-R s/L) over [0, h],
    w_i = (1 - a)/x, w_u = (1 - w_i)/R with x = R h/L, a = exp(-x);
    ``"euler"``: the current is linear over the step, so its mean is (i(t) + i(t+h))/2;
    ``"quasi_static"``: the current is u/R throughout.
    The plant holds the torque it is given over the step, so handing it the mean torque
    transfers the drive's impulse over the step exactly (for the held speed).
    """
    electrical_step_coefficients(R, L, h, method)   # its checks and messages
    w = (ctypes.c_double * 2)()
    _coefficients_kernel("pc_mean_current_coefficients")(R, L, h, ELECTRICAL_METHODS.index(method), w)   # kernels/src/electrics.c
    return w[0], w[1]




def advance_current(i, v, omega, ke, coefficients):
    """Current at the end of a step with held voltage and speed (4.162).

    Parameters
    ----------
    i : float
        Current at the start of the step [A].
    v : float
        Voltage held over the step [V].
    omega : float
        Speed held over the step [rad/s].
    ke : float
        Back-emf constant [V s/rad].
    coefficients : tuple of float
        (a, g) from :func:`electrical_step_coefficients`.

    Returns
    -------
    float
        Current at the end of the step [A].
    """
    a, g = coefficients
    return a * i + g * (v - ke * omega)


def armature_current_rate(i, v, omega, params):
    """di/dt of the armature circuit (4.162): (v - R i - ke omega) / L, for L > 0.

    Parameters
    ----------
    i, v, omega : float
        Current [A], voltage [V], shaft speed [rad/s] at this instant.
    params : motor.presets.MotorParams

    Returns
    -------
    float
        [A/s].
    """
    return kernel.armature_rate(params.R, params.L, params.ke, v, i, omega)   # kernels/src/pc_motor.h


def coulomb_friction(omega, mu, omega_eps):
    """Coulomb friction torque mu sign(omega) of (B.2), regularised.

    Returns ``mu * tanh(omega / omega_eps)``. The drive cannot use a stick
    model: sticking needs the net torque on the rotor and its acceleration,
    which only the plant (that integrates J_rotor) knows, while the drive sees
    omega held over a step. A regularised sign is smooth and odd, gives
    exactly zero torque at rest and +-mu (to 0.1 %) for |omega| > 4 omega_eps.
    Its slope at rest, mu / omega_eps, acts as a viscous damper that the
    co-simulation applies explicitly (torque computed from the omega held at
    the step start); that is stable and non-oscillating when
    h mu / (omega_eps J) < 1, J the inertia seen at the joint. The default
    omega_eps = 0.5 rad/s satisfies this at h = 1 ms for J >= J_rotor of
    both thesis motors (h mu / J_rotor <= 0.30 rad/s).

    Parameters
    ----------
    omega : float
        Shaft speed [rad/s].
    mu : float
        Coulomb friction torque [N m].
    omega_eps : float
        Regularisation width [rad/s], > 0.

    Returns
    -------
    float
        Friction torque [N m] (sign of omega).
    """
    return -kernel.shaft_torque(0.0, 0.0, mu, omega_eps, 0.0, omega)   # B.2's friction term (pc_motor.h)


def shaft_torque(i, omega, params):
    """Torque delivered to the mechanism, kt i - b omega - mu sign(omega) (B.2, B.3).

    Parameters
    ----------
    i : float
        Armature current [A].
    omega : float
        Shaft speed [rad/s].
    params : motor.presets.MotorParams
        Motor parameters (kt, b, mu, omega_eps).

    Returns
    -------
    float
        Torque [N m]; the sign convention is that of the current and speed.
    """
    p = params
    return kernel.shaft_torque(p.kt, p.b, p.mu, p.omega_eps, i, omega)   # kernels/src/pc_motor.h
