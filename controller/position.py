"""The discrete position controller: the unified law of the thesis (7.21-7.22).

At each sample (period T, 1 ms on the bench)::

    e = r_d - r,   s = ddr_d - ddr + kv de + kp e            (6.5, 7.22)
    I <- I + T k sat(s / phi)                               (6.65, integral of 7.21)
    u' = Ĥ (ddr_d + kv de + kp e + I) + ĥ                   (7.21)
    kp = lam^2, kv = 2 lam                                  (7.29-7.30)

with r = q (joint space: the actuated angles q1, q2, world frame) or r = x (task space:
the end effector, m).  With the exact model and k = 0 the closed loop error obeys
ë + kv ė + kp e = 0 (6.12 with δ' = 0); with k != 0, s obeys ds/dt = -k sat(s/phi) (the
integral enters u' with the sign that makes s = -I).  The integral uses the rectangle rule
including the current sample.

Measurements are the joint angles and their derivatives (encoders + derivators); the task
state follows by x = FK(q), dx = J dq, ddx = J ddq + beta (:mod:`controller.kinematics`).
Joint references come from the task references by inverse kinematics and the Jacobians.

Model terms (:mod:`controller.model`) are task-space H, h evaluated at the measured pose;
in joint space the law uses ``H_q = J^T H J`` and ``h_q = J^T (H beta + h)``, so
``u' = J^T (H (J a + beta) + h)`` for the commanded joint acceleration a.  Torques: in joint
space the efforts u' ARE the world torques (tau1, tau2); in task space u' = Z^T u* (5.72):
the exact model solves it with the plant's Z, the tabulated and PD laws use the equivalent
closed form tau = J^T u' (tests check both agree).  Current references: tau_k / kt_k.

PD (k = 0, ĥ = 0, Ĥ = m*·1) and TC (k = 0) are the special cases of 7.2.6; the adaptive
gain of (6.66) is optional (``Strategy.gamma``).  Seed 001's sliding-mode law
(``Strategy.law == "seed001"``, strategies SMCq/SMCx, docs/controller.md) replaces (7.21-7.22)
by s = de + lam e, u' = Ĥ (ddr_d + lam de + k sat(s/phi)) + ĥ, with no integral.

Speed (``kernel``): :meth:`PositionController.step_reference` is the readable law in Python
(~20 µs a sample).  With ``kernel="fast"`` (default) every strategy runs the same sample
compiled (:func:`controller.fastlaw.law_step`, ~2 µs; the exact model's terms from
:func:`plant.fast5r.inverse_terms` at :func:`controller.fastlaw.exact_state`, passed to
:func:`controller.fastlaw.law_terms_step`) and falls back to the reference only to raise
its refusals (or to use the exact model off the table).  ``kernel="python"`` always runs the reference;
``kernel="general"`` also evaluates the exact model with the general numpy algorithm
(:func:`plant.parallel.inverse_dynamics_terms`, ~2 ms).
"""
from __future__ import annotations

import math

import numpy as np

from motor.presets import get_motor_preset
from plant.fast5r import INVERSE_SIZE, inverse_terms
from plant import fivebar
from plant.presets import FiveBarParams

from . import fastlaw
from .fastlaw import S_E, S_INTEGRAL, S_K, S_S, S_S_PREV, law_step
from .kinematics import Kinematics
from .model import DEFAULT_EXTENT, DEFAULT_GRID_STEP, ExactModel, ModelRangeError, TabulatedModel, perturbed_params
from .strategies import Strategy

SAMPLE_TIME = 1e-3
MODEL_KINDS = ("exact", "tabulated")
#: "fast": compiled law (PD, tabulated, exact) and compiled exact model; "python": the reference law
#: in Python (exact model compiled); "general": the reference law with the general exact model.
KERNELS = ("fast", "python", "general")
MEASUREMENTS = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2")
REFERENCES = ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")


def sat(x: float) -> float:
    """Saturation (6.65)."""
    return x if -1.0 <= x <= 1.0 else (1.0 if x > 0.0 else -1.0)


def _sign(x: float) -> float:
    return 0.0 if x == 0.0 else math.copysign(1.0, x)


def default_kt():
    """(kt1, kt2) of the motor presets motor1, motor2 (Tables 16, 18), N m/A."""
    return get_motor_preset("motor1").kt, get_motor_preset("motor2").kt


class PositionController:
    """The unified law (7.21-7.22) for one strategy.

    Parameters
    ----------
    params : FiveBarParams
        The nominal plant (e.g. ``plant.get_preset("bench")``).
    strategy : Strategy
        From :func:`controller.strategies.get_strategy`, possibly modified with ``with_``.
    model : {"exact", "tabulated"}
        Source of Ĥ, ĥ for model-based (TC) strategies; ignored by PD strategies.
    model_error : float
        The model's masses and inertias are (1 + model_error) times the plant's.
    grid_step, extent : float, tuple
        Table of the tabulated model (:class:`controller.model.TabulatedModel`).
    kt : tuple of float
        Torque constants for the current references, N m/A (default: motor presets).
    T : float
        Sample time, s, used when :meth:`step` gets no ``dt``.
    band : float
        References with singularity margin below it are refused.
    cache : bool
        Cache the table on disk.
    kernel : {"fast", "python", "general"}
        See :data:`KERNELS` and the module docstring; all give the same law to round-off.
    table_fallback : bool
        Tabulated model: at a measured pose outside the table or in a cell with a left-out
        corner (near the workspace's edge or the singular band), evaluate the exact model
        there instead of refusing (counted in :attr:`fallbacks`).  The bench triangle's
        upper vertices (7.24) lie within 2.5 mm of the bench's reach.

    Attributes
    ----------
    integral, k, s_prev, s, e : list of float
        The state of the law after the last sample (read only): the integral of
        k sat(s/phi), the sliding gains, s of the previous sample, s and the error e.
    compiled : bool
        True when :meth:`step` runs :func:`controller.fastlaw.law_step`.
    fallbacks : int
        Samples that used the exact model in place of the table (``table_fallback``).
    """

    #: Kernel buffers -> the function giving the words a run changes; a restored FMU state may
    #: not change the others (:mod:`fmus.fmustate`).
    KERNEL_BUFFERS = {"_buf": fastlaw.run_state_words}

    def __init__(self, params: FiveBarParams, strategy: Strategy, model="tabulated", model_error=0.0,
                 grid_step=DEFAULT_GRID_STEP, extent=DEFAULT_EXTENT, kt=None, T=SAMPLE_TIME,
                 band=fivebar.NEAR_SINGULAR_MARGIN, cache=True, kernel="fast", table_fallback=True):
        if kernel not in KERNELS:
            raise ValueError(f"kernel = {kernel!r} is unknown; valid: {', '.join(KERNELS)}")
        if strategy.space not in ("q", "x"):
            raise ValueError(f"strategy.space = {strategy.space!r}: valid: 'q', 'x'")
        for name in ("lam", "phi"):
            value = getattr(strategy, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} = {value!r} must be > 0")
        if not (math.isfinite(strategy.m_star) and strategy.m_star >= 0.0):
            raise ValueError(f"m_star = {strategy.m_star!r} must be >= 0")
        if not strategy.model_based and strategy.m_star <= 0.0:
            raise ValueError(f"m_star = {strategy.m_star!r} must be > 0 for the PD strategy {strategy.name}")
        for i, k in enumerate(strategy.k):
            if not (math.isfinite(k) and k >= 0.0):
                raise ValueError(f"k{i + 1} = {k!r} must be >= 0")
        if strategy.gamma is not None and not all(math.isfinite(g) and g >= 0.0 for g in strategy.gamma):
            raise ValueError(f"gamma = {strategy.gamma!r} must be >= 0")
        if model not in MODEL_KINDS:
            raise ValueError(f"model = {model!r} is unknown; valid: {', '.join(MODEL_KINDS)}")
        if not (math.isfinite(T) and T > 0.0):
            raise ValueError(f"T = {T!r} s must be > 0")
        self.params, self.strategy, self.T, self.band = params.validate(), strategy, float(T), float(band)
        self.kin = Kinematics(params)
        self.kp, self.kv = strategy.lam ** 2, 2.0 * strategy.lam
        self.kt = default_kt() if kt is None else tuple(float(v) for v in kt)
        if not all(math.isfinite(v) and v > 0.0 for v in self.kt):
            raise ValueError(f"kt = {self.kt!r} must be > 0")
        self.model_kind = model if strategy.model_based else None
        self.model = None
        if strategy.model_based:
            model_params = perturbed_params(params, model_error)
            self.model = (ExactModel(model_params, kernel="general" if kernel == "general" else "fast")
                          if model == "exact"
                          else TabulatedModel(model_params, grid_step, extent, cache=cache, band=band))
        self._fallback = (ExactModel(model_params) if strategy.model_based and model == "tabulated"
                          and table_fallback else None)
        self.fallbacks = 0
        self.kernel = kernel
        self.compiled = kernel == "fast"
        # Constants, state and table of the compiled law in one array; the reference keeps its
        # state in the same place (fastlaw.STATE), so both paths can be mixed.
        self._buf = fastlaw.pack(self.kin, self.band, strategy.space, self.model if self.compiled else None,
                                 self.kp, self.kv, strategy.phi, strategy.gamma, strategy.m_star, self.kt,
                                 strategy.law)
        if self.compiled:
            fastlaw.compile_law(exact=self.model_kind == "exact")
        # The exact model's law: the pose's thesis coordinates and the model's terms (5.74-5.77).
        self._q, self._dq, self._terms = np.empty(7), np.empty(7), np.empty(INVERSE_SIZE)
        self.reset()

    def reset(self):
        """Zero the integral of the sliding term and restore the preset gains."""
        self._buf[fastlaw.STATE] = 0.0
        self._buf[S_K:S_K + 2] = self.strategy.k

    # --- state (read only views as lists) ------------------------------------------------
    def _pair(self, index):
        return [float(self._buf[index]), float(self._buf[index + 1])]

    integral = property(lambda self: self._pair(S_INTEGRAL), doc="Integral of k sat(s/phi) (7.21).")
    k = property(lambda self: self._pair(S_K), doc="Sliding gains (constant unless adaptive, 6.66).")
    s_prev = property(lambda self: self._pair(S_S_PREV), doc="s of the previous sample.")
    s = property(lambda self: self._pair(S_S), doc="s of the last sample (7.22).")
    e = property(lambda self: self._pair(S_E), doc="Error r_d - r of the last sample.")

    # --- checks ---------------------------------------------------------------------
    def _reference_angles(self, t, x_d, y_d):
        try:
            angles = self.kin.inverse(x_d, y_d)
        except fivebar.KinematicsError:
            raise ValueError(f"reference (x_d, y_d) = ({x_d!r}, {y_d!r}) m at t = {t:.6g} s "
                             f"is outside the workspace") from None
        p11, p12, p21, p22 = angles
        margin = min(abs(math.sin(p12 - p11)), abs(math.sin(p22 - p21)), abs(math.sin(p12 - p22)))
        if margin < self.band:
            raise ValueError(f"reference (x_d, y_d) = ({x_d!r}, {y_d!r}) m at t = {t:.6g} s is in the "
                             f"near-singular band (margin {margin:.3g} < {self.band:g})")
        return angles

    # --- the law ------------------------------------------------------------------------
    def step(self, t, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, dt=None):
        """One sample of the law (7.21-7.22): (tau1, tau2, i_ref1, i_ref2).

        Arguments, results and refusals as :meth:`step_reference`; compiled when
        :attr:`compiled`.
        """
        if self.compiled:
            r = self._compiled_step(q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d,
                                    self.T if dt is None else dt)
            if r[6] == 0.0:
                return r[:4]
        return self.step_reference(t, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, dt)

    def _compiled_step(self, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, h):
        """The compiled sample (:func:`controller.fastlaw.law_step`, or for the exact model
        :func:`~controller.fastlaw.exact_state`, :func:`plant.fast5r.inverse_terms` and
        :func:`~controller.fastlaw.law_terms_step`); status r[6] != 0: refused, nothing changed."""
        if self.model_kind != "exact":
            return law_step(self._buf, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, h)
        q1, q2, dq1, dq2 = float(q1), float(q2), float(dq1), float(dq2)
        if not fastlaw.exact_state(self._buf, q1, q2, dq1, dq2, self._q, self._dq):
            return (0.0,) * 6 + (fastlaw.REFUSED,)
        inverse_terms(self.model._p, self._q, self._dq, self._terms)
        return fastlaw.law_terms_step(self._buf, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d,
                                      h, self._terms)

    def step_with_errors(self, t, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, dt=None):
        """:meth:`step` and the errors: (tau1, tau2, i_ref1, i_ref2, e1, e2)."""
        if self.compiled:
            r = self._compiled_step(q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d,
                                    self.T if dt is None else dt)
            if r[6] == 0.0:
                return r[:6]
        out = self.step_reference(t, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, dt)
        return out + (float(self._buf[S_E]), float(self._buf[S_E + 1]))

    def step_reference(self, t, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, dt=None):
        """One sample of the law (7.21-7.22), in Python: the reference of the compiled law.

        Parameters
        ----------
        t : float
            Time of the sample, s (for messages only).
        q1 ... ddq2 : float
            Measured actuated angles (world frame, rad) and their first two derivatives.
        x_d ... ddy_d : float
            Task-space reference and its derivatives (m, m/s, m/s^2).
        dt : float, optional
            Integration step of the sliding term, s (default T).

        Returns
        -------
        tau1, tau2, i_ref1, i_ref2 : float
            World torques (CCW positive, N m) and current references tau/kt (A).

        Raises
        ------
        ValueError
            Naming the variable, its value and t: a non-finite input, a reference outside the
            workspace or in the near-singular band, a measured pose without assembly, or a
            pose outside the tabulated model.
        """
        values = (q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d)
        for name, value in zip(MEASUREMENTS + REFERENCES, values):
            if not math.isfinite(value):
                raise ValueError(f"input {name} = {value!r} at t = {t:.6g} s is not finite")
        h = self.T if dt is None else dt
        angles = self._reference_angles(t, x_d, y_d)
        try:
            x, y, dx, dy, ddx, ddy, J, beta = self.kin.task_state(q1, q2, dq1, dq2, ddq1, ddq2)
        except fivebar.KinematicsError as exc:
            raise ValueError(f"measured (q1, q2) = ({q1!r}, {q2!r}) rad at t = {t:.6g} s: {exc}") from None
        st = self.strategy
        if st.space == "x":
            r = (x, y, dx, dy, ddx, ddy)
            rd = (x_d, y_d, dx_d, dy_d, ddx_d, ddy_d)
        else:
            r = (q1, q2, dq1, dq2, ddq1, ddq2)
            rd = self.kin.joint_reference(x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, angles)
        kp, kv, buf = self.kp, self.kv, self._buf
        seed = st.law == "seed001"
        a = [0.0, 0.0]
        for i in (0, 1):
            e, de, dde = rd[i] - r[i], rd[2 + i] - r[2 + i], rd[4 + i] - r[4 + i]
            if seed:                                                              # seed 001, 1.2
                feedback = st.lam * de
                s = de + st.lam * e
            else:
                feedback = kv * de + kp * e
                s = dde + feedback                                                # (7.22)
            k, s_prev, integral = float(buf[S_K + i]), float(buf[S_S_PREV + i]), float(buf[S_INTEGRAL + i])
            if st.gamma is not None:                                              # (6.66)
                same = _sign(s) == _sign(s_prev)
                if abs(s) >= st.phi or not same:
                    k = abs(k + st.gamma[i] * _sign(s) * _sign(s_prev))
            if seed:
                a[i] = rd[4 + i] + feedback + k * sat(s / st.phi)
            else:
                if k != 0.0:
                    integral += h * k * sat(s / st.phi)
                a[i] = rd[4 + i] + feedback + integral                            # (7.21)
            buf[S_K + i], buf[S_INTEGRAL + i], buf[S_S_PREV + i], buf[S_S + i], buf[S_E + i] = k, integral, s, s, e
        J00, J01, J10, J11 = J
        if not st.model_based:                                                    # PD: Ĥ = m*·1, ĥ = 0
            u0, u1 = st.m_star * a[0], st.m_star * a[1]
            if st.space == "q":
                return self._out(u0, u1)
            return self._out(J00 * u0 + J10 * u1, J01 * u0 + J11 * u1)           # tau = J^T u'
        try:
            try:
                H00, H01, H11, h0, h1 = self.model.terms(x, y, dx, dy)
            except ModelRangeError:
                if self._fallback is None:
                    raise
                H00, H01, H11, h0, h1 = self._fallback.terms(x, y, dx, dy)
                self.fallbacks += 1
        except (ModelRangeError, fivebar.KinematicsError) as exc:
            raise ValueError(f"measured pose (x, y) = ({x:.6g}, {y:.6g}) m at t = {t:.6g} s: {exc}") from None
        if st.space == "x":
            u0, u1 = H00 * a[0] + H01 * a[1] + h0, H01 * a[0] + H11 * a[1] + h1   # (7.21)
            if self.model_kind == "exact":                                        # u' = Z^T u* (5.72)
                Z = self.model.last_Z
                det = Z[0, 0] * Z[1, 1] - Z[0, 1] * Z[1, 0]
                us0 = (Z[1, 1] * u0 - Z[1, 0] * u1) / det                         # Z^T = [[Z00, Z10], [Z01, Z11]]
                us1 = (-Z[0, 1] * u0 + Z[0, 0] * u1) / det
                return self._out(us0, -us1)                                       # tau2 = -u*_theta21
            return self._out(J00 * u0 + J10 * u1, J01 * u0 + J11 * u1)
        # Joint space: u' = J^T (H (J a + beta) + h).
        ax = J00 * a[0] + J01 * a[1] + beta[0]
        ay = J10 * a[0] + J11 * a[1] + beta[1]
        f0, f1 = H00 * ax + H01 * ay + h0, H01 * ax + H11 * ay + h1
        return self._out(J00 * f0 + J10 * f1, J01 * f0 + J11 * f1)

    def _out(self, tau1, tau2):
        return tau1, tau2, tau1 / self.kt[0], tau2 / self.kt[1]
