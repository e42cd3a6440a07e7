"""Time stepping of any mechanism of :mod:`plant.spec` with the general algorithm (ch. 4-5).

:class:`SpecSimulator` is the spec-built counterpart of :class:`plant.PlantSimulator`:
the state is ``[q, dq]`` with ``q = [q_0, q_1, ..., q_n]`` (5.5), the forward dynamics
(5.66) of :func:`plant.parallel.forward_dynamics` with Baumgarte stabilisation, the
torques held over a communication step, RK4 or Dormand-Prince 5(4)
(:class:`plant.IntegratorSettings`; the kernel is always "general").

The start configuration is found from the platform's start position by
:func:`assemble`: continuation from the spec's working-mode pose, Newton steps on the
loop closure (5.18) at each point, so that the solution stays on the working mode's
branch.
"""
from __future__ import annotations

import math

import numpy as np

from kernels import timed

from .integrators import IntegrationError, WorkLimitError, dopri5, rk4
from .parallel import forward_dynamics, left_inverse_solve, mechanism_state
from .serial import chain_dynamics, chain_kinematics
from .simulator import BAUMGARTE_RK4_LIMIT, RESIDUAL_STOP, IntegratorSettings, PlantError
from .spec import PlantSpec

#: Newton's tolerance on the loop-closure residual when assembling [m].
ASSEMBLY_TOLERANCE = 1e-14
#: Straight-line steps from the working-mode pose to the start point.
CONTINUATION_STEPS = 20


class AssemblyError(ValueError):
    """The mechanism cannot be assembled with its platform at the requested point."""


def reference_pose(spec: PlantSpec) -> np.ndarray:
    """q at the working-mode pose: the joints' ``mode`` values, the platform where the
    chains' tips put it (their mean)."""
    mech = spec.mechanism
    q = np.zeros(mech.n_coordinates)
    for k, _, info in spec.joints():
        q[k] = info.mode
    _, qs = mech.split(q)
    points = [np.asarray(c.base) + np.asarray(c.rotation) @ chain_kinematics(c.chain, qi, np.zeros_like(qi)).tip
              - np.asarray(c.attach) for c, qi in zip(spec.chains, qs)]
    q[:3] = np.mean(points, axis=0)
    return q


def assemble(spec: PlantSpec, start) -> np.ndarray:
    """q with the platform's independent coordinates at ``start`` and the loop closed.

    Continuation along the straight line from :func:`reference_pose`, Newton on the
    redundant coordinates q° at each point ((A Q°)^-1 of 5.54, least squares for the
    redundant rows).

    Raises
    ------
    AssemblyError
        Newton fails on the way (the point is out of reach or a singularity lies between).
    """
    mech = spec.mechanism
    Qo = mech.Q_redundant
    idx = list(spec.independent)
    q = reference_pose(spec)
    q = _close(mech, q, Qo, tol=1e-9, label="the working-mode pose")   # the mode values need not close exactly
    origin = q[idx].copy()
    target = np.asarray(start, dtype=float)[idx]
    for s in np.linspace(0.0, 1.0, CONTINUATION_STEPS + 1)[1:]:
        q[idx] = origin + s * (target - origin)
        q = _close(mech, q, Qo, tol=ASSEMBLY_TOLERANCE if s == 1.0 else 1e-10,
                   label=f"platform at {np.round(q[:3], 6).tolist()}")
    return q


def _close(mech, q, Qo, tol, label, iterations=50):
    dq = np.zeros_like(q)
    for _ in range(iterations):
        st = mechanism_state(mech, q, dq)
        if np.linalg.norm(st.residual) <= tol:
            return q
        q = q - Qo @ left_inverse_solve(st.A @ Qo, st.residual)
        if not np.all(np.isfinite(q)):
            break
    st = mechanism_state(mech, q, dq)
    if np.linalg.norm(st.residual) <= max(tol, 1e-12):
        return q
    raise AssemblyError(f"cannot close the loop with the {label}: residual {np.linalg.norm(st.residual):.3g} m "
                        "after Newton (out of reach, or a singularity between it and the working-mode pose)")


class SpecSimulator:
    """A spec's parallel mechanism, stepped over communication steps with torques held.

    Parameters
    ----------
    spec : PlantSpec
        A parallel mechanism (with a ``[platform]``).
    start : sequence of 3 float, optional
        Platform start position [m] (the spec's ``start`` by default); at rest.
    settings : IntegratorSettings
        ``kernel`` must be "general" (the compiled kernel is the 5R's alone).
    """

    def __init__(self, spec: PlantSpec, start=None, settings: IntegratorSettings = IntegratorSettings(kernel="general")):
        if not spec.is_parallel:
            raise ValueError(f"{spec.source}: a serial chain (no [platform]) cannot be simulated as a plant")
        self.settings = settings.validate()
        if settings.kernel != "general" or settings.project:
            raise ValueError(f"kernel = {settings.kernel!r}, project = {settings.project!r}: a spec plant "
                             "runs the general kernel without projection")
        self.spec = spec
        self.mechanism = spec.mechanism
        start = spec.start if start is None else tuple(float(v) for v in start)
        if len(start) != 3 or not all(math.isfinite(v) for v in start):
            raise ValueError(f"start = {start!r} must be 3 finite numbers [m]")
        q = assemble(spec, start)
        self.y = np.concatenate([q, np.zeros_like(q)])
        self.time = 0.0
        self._h_next = None

    def derivative(self, y, u_star):
        n = y.size // 2
        return np.concatenate([y[n:], forward_dynamics(self.mechanism, y[:n], y[n:], u_star, self.settings.baumgarte)])

    def step(self, torques, dt: float, max_evaluations: int | None = None) -> int:
        """Advance by dt with ``torques`` (one per actuated joint, :attr:`PlantSpec.inputs`
        order) held; return the right-hand-side evaluations taken.  The state is kept on error
        (:class:`PlantError`; :class:`plant.integrators.WorkLimitError` when dopri5 reaches
        ``max_evaluations``, None: unbounded)."""
        torques = np.asarray(torques, dtype=float)
        if torques.shape != (len(self.spec.inputs),):
            raise timed(PlantError(f"{torques.size} torques given for the {len(self.spec.inputs)} inputs "
                                   f"{', '.join(self.spec.inputs)} at t = {self.time:.6g} s"))
        for name, value in zip(self.spec.inputs, torques.tolist()):
            if not math.isfinite(value):
                raise timed(PlantError(f"input {name} = {value!r} at t = {self.time:.6g} s is not finite"))
        if not (math.isfinite(dt) and dt > 0.0):
            raise timed(PlantError(f"step size {dt!r} at t = {self.time:.6g} s must be > 0"))
        s = self.settings
        if s.method == "rk4" and s.baumgarte * dt / s.substeps > BAUMGARTE_RK4_LIMIT:
            raise PlantError(f"baumgarte = {s.baumgarte!r} /s with RK4 steps of {dt / s.substeps:.6g} s: "
                             f"baumgarte * h > {BAUMGARTE_RK4_LIMIT:g}, use more substeps or dopri5")
        held = ", ".join(f"{n} = {v!r}" for n, v in zip(self.spec.inputs, torques.tolist())) + " N m held"
        f = lambda z: self.derivative(z, torques)   # noqa: E731
        try:
            if s.method == "rk4":
                y, evaluations = rk4(f, self.y, dt, s.substeps), 4 * s.substeps
            else:
                y, self._h_next, _, evaluations = dopri5(f, self.y, dt, s.rtol, s.atol, self._h_next,
                                                         max_evaluations=max_evaluations)
        except WorkLimitError:
            raise
        except (IntegrationError, np.linalg.LinAlgError) as exc:
            raise timed(PlantError(f"integration failed in the step from t = {self.time:.6g} s ({held}): "
                                   f"{exc}")) from None
        if not np.all(np.isfinite(y)):
            raise timed(PlantError(f"state became non-finite in the step from t = {self.time:.6g} s ({held})"))
        residual = self._residual_of(y)
        if not residual <= RESIDUAL_STOP:
            raise timed(PlantError(f"integration diverged in the step from t = {self.time:.6g} s ({held}): "
                                   f"loop-closure residual {residual:.3g} m > {RESIDUAL_STOP:g} m (a singular pose or too fast a "
                                   "motion for the step: use substeps or dopri5)"))
        self.y = y
        self.time += dt
        return evaluations

    def _residual_of(self, y) -> float:
        n = y.size // 2
        return float(np.linalg.norm(mechanism_state(self.mechanism, y[:n], y[n:]).residual))

    def residual_norm(self) -> float:
        """Norm of the loop-closure residual q̄(q) (5.18) [m]."""
        return self._residual_of(self.y)

    def outputs(self) -> dict:
        """Platform position ``x, y, z`` and velocity ``dx, dy, dz``; every joint by name and
        its rate ``d<name>``; ``residual``."""
        n = self.y.size // 2
        q, dq = self.y[:n].tolist(), self.y[n:].tolist()
        out = {a: q[i] for i, a in enumerate("xyz")}
        out.update({f"d{a}": dq[i] for i, a in enumerate("xyz")})
        for k, _, info in self.spec.joints():
            out[info.name] = q[k]
            out[f"d{info.name}"] = dq[k]
        out["residual"] = self.residual_norm()
        return out


def serial_terms(spec: PlantSpec, q, dq, chain: int = 0):
    """M*, v*, g* (4.138) of one chain of the spec, gravity rotated into its base frame."""
    c = spec.chains[chain]
    gravity = np.asarray(c.rotation).T @ np.asarray(spec.gravity)
    return chain_dynamics(c.chain, q, dq, gravity)
