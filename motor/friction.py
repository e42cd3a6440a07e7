"""LuGre friction with stiction (Canudas de Wit, Olsson, Åström, Lischinsky, IEEE TAC 40(3), 1995).

The paper's model, its equation numbers, written for a rotating shaft (angle in rad, torque
in N m) — the same equations hold for a sliding mass (m, N) and the tests use both:

    dz/dt = ω − σ0 |ω| z / G(ω)                            (1), with G = σ0 g
    G(ω)  = Fc + (Fs − Fc) exp(−(ω/ωs)²)                    (3)
    F     = σ0 z + σ1 dz/dt + σ2 ω                          (4)  (2 is 4 without σ2 ω)

z is the mean bristle deflection [rad], G(ω) the Stribeck curve [N m] (Fc the Coulomb torque,
Fs the break-away torque, ωs the Stribeck speed [rad/s]), σ0 the bristle stiffness [N m/rad],
σ1 the bristle damping [N m s/rad], σ2 the viscous coefficient [N m s/rad].  At constant
speed z tends to the steady deflection sign(ω) G(ω)/σ0 and F to the static map
sign(ω) G(ω) + σ2 ω (the paper's (5)); below Fs a held torque deflects the bristles by about
F/σ0 and nothing slides (presliding).

Over a step of length h with the speed ω held (the drive's zero-order-hold input), (1) is
linear in z with rate r = σ0 |ω| / G(ω), so :func:`advance` solves it exactly:

    z(h) = z0 e^{−rh} + ω h φ1(rh),        mean z = z0 φ1(rh) + ω h φ2(rh),
    φ1(x) = (1 − e^{−x}) / x,               φ2(x) = (x − 1 + e^{−x}) / x²,

so the bristle model itself is stable for any step; what can go unstable is the loop that
feeds ω back through an inertia held over the step (docs/friction.md measures the limit).

Named layout of a friction array (:func:`new_lugre`): the parameters :data:`F_FC` ...
:data:`F_SIGMA2`, then the state :data:`F_Z`.  Kernels return a status first (:data:`OK` or
:data:`NONFINITE_INPUT`, nothing changed); they call no compiled function of another file
(numba's cache watches one file).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from motor._checks import BadValue

OK = 0
#: The speed is NaN or infinite.
NONFINITE_INPUT = 1

#: Layout of a friction array: Fc, Fs [N m], ωs [rad/s], σ0 [N m/rad], σ1, σ2 [N m s/rad] ...
F_FC, F_FS, F_OMEGA_S, F_SIGMA0, F_SIGMA1, F_SIGMA2 = 0, 1, 2, 3, 4, 5
#: ... and the state: the bristle deflection z [rad].
F_Z = 6
FRICTION_SIZE = 7

#: The drive's names (:class:`motor.MotorParams`) of the parameters it calls otherwise.
_DRIVE_NAMES = {"Fc": "mu", "Fs": "mu_s", "sigma2": "b"}

# Below this r h, φ2 by its series (the closed form loses all digits to cancellation).
_SERIES_BELOW = 1e-3


@dataclass(frozen=True)
class LuGre:
    """Parameters of the LuGre model (1)-(4), validated.

    Parameters
    ----------
    Fc : float
        Coulomb torque [N m], > 0 (the sliding friction at high speed).
    Fs : float
        Break-away (static) torque [N m], >= Fc.
    omega_s : float
        Stribeck speed [rad/s], > 0.
    sigma0 : float
        Bristle stiffness [N m/rad], > 0.
    sigma1 : float
        Bristle damping [N m s/rad], >= 0.
    sigma2 : float
        Viscous coefficient [N m s/rad], >= 0.

    Raises
    ------
    motor._checks.BadValue
        Naming the first bad parameter and its value; its ``name`` is the drive's name for
        the parameter (:class:`motor.MotorParams`: Fc is ``mu``, Fs ``mu_s``, σ2 ``b``), which
        the message gives beside the paper's symbol.
    """

    Fc: float
    Fs: float
    omega_s: float
    sigma0: float
    sigma1: float
    sigma2: float

    def __post_init__(self):
        for field in ("Fc", "Fs", "omega_s", "sigma0", "sigma1", "sigma2"):
            value, name = getattr(self, field), _DRIVE_NAMES.get(field, field)
            label = "LuGre friction: " + (f"{field} ({{name}})" if field in _DRIVE_NAMES else "{name}")
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise BadValue(name, value, label + " = {value!r} must be a finite number")
            if field in ("Fc", "omega_s", "sigma0") and not value > 0.0:
                raise BadValue(name, value, label + " = {value!r} must be > 0")
            if value < 0.0:
                raise BadValue(name, value, label + " = {value!r} must be >= 0")
        if self.Fs < self.Fc:
            raise BadValue("mu_s", self.Fs, "LuGre friction: the break-away torque Fs ({name}) = {value!r} must be "
                           ">= the Coulomb torque Fc ({other}) = {other_value!r}", "mu", self.Fc)

    @classmethod
    def of_motor(cls, params) -> "LuGre":
        """The LuGre model of a :class:`motor.MotorParams`: Fc = mu, Fs = mu_s, ωs = omega_s,
        σ0 = sigma0, σ1 = sigma1, σ2 = b."""
        return cls(params.mu, params.mu_s, params.omega_s, params.sigma0, params.sigma1, params.b)


def new_lugre(model: LuGre, z0: float = 0.0) -> np.ndarray:
    """A friction array (layout above) for ``model`` with bristle deflection ``z0``."""
    f = np.zeros(FRICTION_SIZE)
    f[F_FC], f[F_FS], f[F_OMEGA_S] = model.Fc, model.Fs, model.omega_s
    f[F_SIGMA0], f[F_SIGMA1], f[F_SIGMA2] = model.sigma0, model.sigma1, model.sigma2
    f[F_Z] = z0
    return f


@njit(cache=True)
def stribeck(f, omega):
    """G(ω) = Fc + (Fs − Fc) exp(−(ω/ωs)²) [N m] (3)."""
    s = omega / f[F_OMEGA_S]
    return f[F_FC] + (f[F_FS] - f[F_FC]) * math.exp(-s * s)


@njit(cache=True)
def bristle_rate(f, z, omega):
    """dz/dt = ω − σ0 |ω| z / G(ω) (1)."""
    return _bristle_rate(f, z, omega, stribeck(f, omega))


@njit(cache=True)
def _bristle_rate(f, z, omega, g):
    """(1) with G(ω) = ``g`` already evaluated."""
    return omega - f[F_SIGMA0] * abs(omega) * z / g


@njit(cache=True)
def friction_force(f, z, omega):
    """F = σ0 z + σ1 dz/dt + σ2 ω (4) at deflection z and speed ω."""
    return _friction_force(f, z, omega, stribeck(f, omega))


@njit(cache=True)
def _friction_force(f, z, omega, g):
    """(4) with G(ω) = ``g`` already evaluated."""
    return f[F_SIGMA0] * z + f[F_SIGMA1] * _bristle_rate(f, z, omega, g) + f[F_SIGMA2] * omega


@njit(cache=True)
def steady_deflection(f, omega):
    """The deflection (1) tends to at constant ω: sign(ω) G(ω)/σ0 (0 at ω = 0)."""
    if omega == 0.0:
        return 0.0
    return math.copysign(stribeck(f, omega), omega) / f[F_SIGMA0]


@njit(cache=True)
def _phi(x):
    """φ1(x) = (1 − e^{−x})/x and φ2(x) = (x − 1 + e^{−x})/x², x >= 0."""
    if x < _SERIES_BELOW:
        return 1.0 - x * (0.5 - x * (1.0 / 6.0 - x / 24.0)), 0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x / 120.0))
    e = math.expm1(-x)           # e^{-x} - 1
    return -e / x, (x + e) / (x * x)


@njit(cache=True)
def advance(f, z0, omega, h):
    """(z, F_end, F_mean): (1) solved exactly over h with ω held, from z0.

    ``z`` is the deflection at the step's end, ``F_end`` the friction (4) there, ``F_mean``
    the friction averaged over the step (σ0 mean z + σ1 (z − z0)/h + σ2 ω).
    """
    g = stribeck(f, omega)                                      # once: the rate and F_end need it
    x = f[F_SIGMA0] * abs(omega) / g * h                        # r h
    phi1, phi2 = _phi(x)
    z = z0 * math.exp(-x) + omega * h * phi1
    mean_z = z0 * phi1 + omega * h * phi2
    f_end = _friction_force(f, z, omega, g)
    f_mean = f[F_SIGMA0] * mean_z + f[F_SIGMA1] * (z - z0) / h + f[F_SIGMA2] * omega
    return z, f_end, f_mean


@njit(cache=True)
def friction_peek(f, omega, h):
    """(status, z, F_end, F_mean): :func:`advance` from the array's deflection, nothing
    changed; :func:`friction_commit` keeps z once the caller's step is accepted."""
    if not math.isfinite(omega):
        return NONFINITE_INPUT, 0.0, 0.0, 0.0
    z, f_end, f_mean = advance(f, f[F_Z], omega, h)
    return OK, z, f_end, f_mean


@njit(cache=True)
def friction_commit(f, z):
    """Keep the deflection z of an accepted step."""
    f[F_Z] = z
