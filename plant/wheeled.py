"""The two-wheeled inverted pendulum of seed 000: parameters, simulator, linearisation.

The physics is the C kernel ``kernels/src/wheeled.c`` (bound in :mod:`plant.wheeled_kernel`);
this module holds the parameters (single source of truth, seed 000's values), the state
buffer and the kernel's refusals as :class:`kernels.Refused`.  ``model="exact"`` applies the
rolling constraints by Lagrange-d'Alembert; ``model="seed"`` is seed 000's equations
(16)-(18) with its printed typos corrected but without the two nonholonomic terms
(docs/pendulum.md).

Conventions (docs/contract.md, the brief ../shared/spec/SYSTEM.md section 7): theta is the mean wheel angle from the
vertical (x' = R theta' cos phi), psi the pitch (0 upright, + leaning toward the heading),
phi the yaw (CCW from +x); theta_l,r = theta -+ W/(2R) phi (10); the motors turn the wheels
relative to the body: omega_l,r = theta_l,r' - psi'.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace

import numpy as np

import kernels

from . import wheeled_kernel as kernel

MODELS = ("exact", "seed")
#: The parameters that must be > 0 (the others must be >= 0).
POSITIVE = ("R", "M", "W", "L")


@dataclass(frozen=True)
class WheeledParams:
    """Seed 000's mechanical parameters (SI), its values as defaults.

    g gravity; m, R, J_w one wheel's mass, radius, spin inertia (m R^2/2); M, W, D, H the
    body's mass, width, depth, height; L axle to body centre of mass (H/2); J_psi, J_phi the
    body's pitch and yaw inertias (M L^2/3, M (W^2 + D^2)/12).
    """

    g: float = 9.8
    m: float = 0.03
    R: float = 0.04
    J_w: float = 0.03 * 0.04 ** 2 / 2.0
    M: float = 0.6
    W: float = 0.14
    D: float = 0.04
    H: float = 0.144
    L: float = 0.144 / 2.0
    J_psi: float = 0.6 * (0.144 / 2.0) ** 2 / 3.0
    J_phi: float = 0.6 * (0.14 ** 2 + 0.04 ** 2) / 12.0

    def validate(self) -> "WheeledParams":
        """Raise ValueError naming the first non-finite or non-physical parameter: all
        must be finite, R, M, W, L > 0 and the others >= 0."""
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise ValueError(f"parameter {f.name} = {value!r} is not a finite number")
            if f.name in POSITIVE and not value > 0.0:
                raise ValueError(f"parameter {f.name} = {value!r} must be > 0")
            if value < 0.0:
                raise ValueError(f"parameter {f.name} = {value!r} must be >= 0")
        return self

    def with_(self, **changes) -> "WheeledParams":
        """A validated copy with some parameters replaced (ValueError for unknown names)."""
        unknown = sorted(set(changes) - {f.name for f in fields(self)})
        if unknown:
            raise ValueError(f"unknown pendulum parameter(s) {unknown}")
        return replace(self, **changes).validate()


SEED = WheeledParams()


def pack(params: WheeledParams, model: str = "exact", yaw: bool = True) -> np.ndarray:
    """The kernel's parameter buffer (float64, ``pc_wheeled_params``'s layout)."""
    if model not in MODELS:
        raise ValueError(f"model = {model!r}; valid: {', '.join(MODELS)}")
    prm = kernel.new_params()
    for name, value in asdict(params.validate()).items():
        prm[kernel.PARAMS[name]] = value
    prm[kernel.PARAMS["nonholonomic"]] = 1.0 if model == "exact" else 0.0
    prm[kernel.PARAMS["yaw"]] = 1.0 if yaw else 0.0
    return prm


_FELL = "at t = {time:.6g} s: psi = {psi_deg:.4g} deg at the last good state"
#: The kernel's refusal codes -> their record and message (``psi_deg``: the pitch at the last
#: good state [deg], the start of the step).
REASONS = {
    kernel.FALLEN_PITCH: kernels.Reason("fallen_pitch", ("psi",), "rad",
                                        "the robot fell over (pitch beyond 90 degrees) " + _FELL),
    kernel.FALLEN_FLOOR: kernels.Reason("fallen_floor", ("psi",), "rad",
                                        "the robot fell over (body touching the floor) " + _FELL),
    kernel.NONFINITE: kernels.Reason("nonfinite_state", kernel.STATE_NAMES, "", "the state became non-finite " + _FELL),
    kernel.BAD_INPUT: kernels.Reason("input_not_finite", kernel.INPUT_NAMES, "N m",
                                     "input {variable} = {value!r} at t = {time:.6g} s is not finite"),
    kernel.BAD_STEP: kernels.Reason("bad_step", ("dt",), "s", "step size {value!r} at t = {time:.6g} s must be > 0"),
    kernel.BAD_SETTING: kernels.Reason("bad_setting", ("substeps", "count"), "",
                                       "setting {variable} = {value!r} at t = {time:.6g} s is out of range (substeps: "
                                       f"an integer in [1, {kernel.MAX_SUBSTEPS}]; count: > 0 rad)"),
    kernel.INPUT_LIMIT: kernels.Reason("input_absurd", kernel.INPUT_NAMES, "N m",
                                       "input {variable} = {value!r} at t = {time:.6g} s is absurd: "
                                       "|{variable}| must be <= {limit:g}"),
}


class FallenError(kernels.Refused, RuntimeError):
    """The robot fell over (or its state became non-finite) within a step: the kernel's
    refusal record (:class:`kernels.Refused`: ``variable`` psi or the non-finite state entry,
    its ``value`` at the end of the failing substep, ``time`` the end of that substep [s]).

    Attributes
    ----------
    code : int
        the kernel's refusal code (:data:`REASONS` key).
    psi : float
        Pitch at the last good state [rad].
    """

    def __init__(self, refused: kernels.Refused, psi: float):
        record = refused.record()
        message = record.pop("message")
        super().__init__(message, **record, names_time=refused.names_time)
        self.psi = psi


def refusal_error(refusal: kernels.Refusal, time: float, psi: float, limit: float = math.inf) -> kernels.Refused:
    """The exception of a kernel refusal at ``time`` [s] (a fall: :class:`FallenError`, with
    ``psi`` the pitch at the last good state [rad])."""
    refused = kernels.refused(REASONS, refusal, time, psi_deg=math.degrees(psi), limit=limit)
    return FallenError(refused, psi) if refusal.code in kernel.FALLS else refused


def initial_refusal(refusal: kernels.Refusal) -> ValueError:
    """The refusal of an initial state the kernel's condition refuses: the state entry and its
    value as fields (:class:`motor._checks.BadValue`, which a slave renames to its parameter),
    the reason :data:`REASONS` names for the code."""
    from motor._checks import BadValue   # the motor package imports python-control: only here

    reason = REASONS[refusal.code]
    unit = f" {reason.unit}" if reason.unit else ""
    return BadValue(reason.variables[refusal.index], float(refusal.value),
                    "initial {name} = {value!r}" + unit + f" is no standing robot ({reason.name})")


#: Default RK4 substeps per 1 ms communication step: 2 keeps the error below 1e-9 rad
#: against a tight-tolerance solution (docs/pendulum.md, tests/plant/test_wheeled.py).
SUBSTEPS = 2
MAX_SUBSTEPS = kernel.MAX_SUBSTEPS


class WheeledPendulum:
    """The pendulum's state and its stepping (the FMU ``WheeledPendulum`` is a thin adapter).

    :attr:`prm` and :attr:`y` are the kernel's parameter and state buffers (float64, the C
    structs' layouts; an FMU state lays saved values over them).

    Parameters
    ----------
    params : WheeledParams
    model : {"exact", "seed"}
    yaw : bool
        False locks the yaw (a straight-line scene): phi' = 0, phi'' = 0.
    initial : dict
        Any of theta, psi, phi, x, y, dtheta, dpsi, dphi (default 0).
    substeps : int
        RK4 steps per communication step.
    encoder_counts : int
        Counts per revolution of the wheel encoders (quadrature).
    """

    def __init__(self, params: WheeledParams = SEED, model: str = "exact", yaw: bool = True,
                 initial: dict | None = None, substeps: int = SUBSTEPS, encoder_counts: int = 4096):
        self.params = params.validate()
        self.model = model
        self.prm = pack(params, model, yaw)
        if not (isinstance(substeps, int) and 1 <= substeps <= MAX_SUBSTEPS):
            raise ValueError(f"parameter substeps = {substeps!r} must be an integer in [1, {MAX_SUBSTEPS}]")
        if not (isinstance(encoder_counts, int) and encoder_counts > 0):
            raise ValueError(f"parameter encoder_counts = {encoder_counts!r} must be a positive integer")
        self.substeps = substeps
        self.count = 2.0 * math.pi / encoder_counts
        self.y = np.zeros(kernel.N_STATE)
        for name, value in (initial or {}).items():
            if name not in kernel.STATE_NAMES:
                raise ValueError(f"unknown initial state {name!r}; valid: {', '.join(kernel.STATE_NAMES)}")
            if not math.isfinite(value):
                raise ValueError(f"initial {name} = {value!r} is not finite")
            self.y[kernel.STATE[name]] = value
        if not yaw and self.y[kernel.DPHI] != 0.0:
            from motor._checks import BadValue   # the motor package imports python-control: only here

            raise BadValue("dphi", float(self.y[kernel.DPHI]),
                           "initial {name} = {value!r} with the yaw locked (yaw = false) must be 0")
        refusal = kernels.Refusal()
        if kernel.condition(self.prm, self.y, refusal) != kernel.OK:
            raise initial_refusal(refusal)
        self.time = 0.0
        self.fallen = False

    def _calls(self) -> kernel.Calls:
        return kernel.calls(self)

    def derivative(self, y, tau_l: float = 0.0, tau_r: float = 0.0, tau_d: float = 0.0) -> np.ndarray:
        """dy/dt at state y (layout :data:`plant.wheeled_kernel.STATE`)."""
        out = np.empty(kernel.N_STATE)
        kernel.derivative(self.prm, y, float(tau_l), float(tau_r), float(tau_d), out)
        return out

    def step(self, tau_l: float, tau_r: float, dt: float, tau_d: float = 0.0) -> None:
        """Advance by dt with the torques held.

        Raises
        ------
        kernels.Refused
            A non-finite torque or a step that is not finite and > 0 (naming it and the time).
        FallenError
            The robot fell within the step (:attr:`fallen` becomes True, the state stays the
            last good one).
        """
        b = self._calls()
        code = b.step(tau_l, tau_r, tau_d, dt, self.substeps)
        if code != kernel.OK:
            if code in kernel.FALLS:
                self.fallen = True
                end = self.time + dt * b.taken.value / self.substeps
            else:
                end = self.time
            raise refusal_error(b.refusal, end, float(self.y[kernel.PSI])) from None
        self.time += dt

    def energy(self) -> float:
        """Kinetic plus potential energy [J]."""
        return self._calls().energy()

    def outputs(self) -> dict:
        """The WheeledPendulum outputs (docs/contract.md), as Python floats (:func:`plant.wheeled_kernel.sensors`)."""
        b = self._calls()
        b.sensors(self.count)
        return dict(zip(kernel.OUTPUT_NAMES, b.out.tolist()))


def upright_mass_matrix(p: WheeledParams):
    """M(psi = 0) of (18): the 2x2 (theta, psi) block and M33."""
    m11 = (2.0 * p.m + p.M) * p.R ** 2 + 2.0 * p.J_w
    m12 = p.M * p.R * p.L
    m22 = p.M * p.L ** 2 + p.J_psi
    m33 = 0.5 * p.m * p.W ** 2 + p.J_phi + p.W ** 2 / (2.0 * p.R ** 2) * p.J_w
    return np.array([[m11, m12], [m12, m22]]), m33


def upright_linearisation(params: WheeledParams = SEED):
    """(A, B) of the pendulum linearised at the upright at rest, x' = A x + B u.

    State x = (theta, psi, phi, theta', psi', phi'), input u = (tau_l, tau_r) [N m].  The
    velocity-quadratic terms, the nonholonomic ones included, vanish to first order, so the
    exact and the seed's models share it; yaw decouples from pitch.
    """
    p = params.validate()
    pitch, m33 = upright_mass_matrix(p)
    inverse = np.linalg.inv(pitch)
    A = np.zeros((6, 6))
    A[0:3, 3:6] = np.eye(3)
    A[3:5, 1] = inverse @ np.array([0.0, p.M * p.g * p.L])   # -G2 = M g L psi to first order
    E = np.array([[1.0, 1.0], [-1.0, -1.0]])                   # (20), theta and psi rows
    B = np.zeros((6, 2))
    B[3:5, :] = inverse @ E
    B[5, :] = np.array([-1.0, 1.0]) * p.W / (2.0 * p.R) / m33
    return A, B
