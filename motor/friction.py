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

A friction array (:func:`new_lugre`) is laid out as the C struct ``pc_lugre``
(kernels/src/drive.h): the parameters, then the state ``z``; the functions below call the C
kernel (kernels/src/drive.c), which the drive's step uses too.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import kernels
from motor import kernel
from motor._checks import BadValue

#: Index of the state (the bristle deflection z [rad]) in a friction array.
F_Z = kernel.index(kernel.LUGRE, "z")
FRICTION_SIZE = kernels.size(kernel.LUGRE)

#: The drive's names (:class:`motor.MotorParams`) of the parameters it calls otherwise.
_DRIVE_NAMES = {"Fc": "mu", "Fs": "mu_s", "sigma2": "b"}


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
    """A friction array (the C struct ``pc_lugre``) for ``model`` with bristle deflection ``z0``."""
    f = np.zeros(FRICTION_SIZE)
    for field in ("Fc", "Fs", "omega_s", "sigma0", "sigma1", "sigma2"):
        f[kernel.LUGRE[field]] = getattr(model, field)
    f[F_Z] = z0
    return f


def stribeck(f: np.ndarray, omega: float) -> float:
    """G(ω) = Fc + (Fs − Fc) exp(−(ω/ωs)²) [N m] (3)."""
    return kernel.lugre_stribeck(kernels.address(f), omega)


def bristle_rate(f: np.ndarray, z: float, omega: float) -> float:
    """dz/dt = ω − σ0 |ω| z / G(ω) (1)."""
    return kernel.lugre_bristle_rate(kernels.address(f), z, omega)


def friction_force(f: np.ndarray, z: float, omega: float) -> float:
    """F = σ0 z + σ1 dz/dt + σ2 ω (4) at deflection z and speed ω."""
    return kernel.lugre_force(kernels.address(f), z, omega)


def steady_deflection(f: np.ndarray, omega: float) -> float:
    """The deflection (1) tends to at constant ω: sign(ω) G(ω)/σ0 (0 at ω = 0)."""
    return kernel.lugre_steady_deflection(kernels.address(f), omega)


def phi(x: float) -> tuple:
    """(φ1(x), φ2(x)) = ((1 − e^{−x})/x, (x − 1 + e^{−x})/x²), x >= 0 (a series below 1e-3)."""
    out = np.empty(2)
    kernel.lugre_phi(x, kernels.address(out))
    return float(out[0]), float(out[1])


def advance(f: np.ndarray, z0: float, omega: float, h: float) -> tuple:
    """(z, F_end, F_mean): (1) solved exactly over h with ω held, from z0.

    ``z`` is the deflection at the step's end, ``F_end`` the friction (4) there, ``F_mean``
    the friction averaged over the step (σ0 mean z + σ1 (z − z0)/h + σ2 ω).
    """
    out = np.empty(3)
    kernel.lugre_advance(kernels.address(f), z0, omega, h, kernels.address(out))
    return float(out[0]), float(out[1]), float(out[2])
