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

One C kernel computes every sample (``kernels/src/law.c``, :mod:`controller.law`): the
checks, the kinematics, the table's interpolation, the law and the torques.  The exact model's
terms come from :func:`plant.fast5r.inverse_terms` (``kernel="fast"``) or the general algorithm
(:func:`plant.parallel.inverse_dynamics_terms`, ``kernel="general"``, ~2 ms) at the measured
pose's thesis coordinates, which the kernel computes; a refused sample becomes one
:class:`kernels.Refused` naming the variable, its value and the time.
"""
from __future__ import annotations

import math

import numpy as np

import kernels
from motor.presets import get_motor_preset
from plant import fivebar
from plant.fast5r import INVERSE_SIZE, inverse_terms
from plant.parallel import inverse_dynamics_terms
from plant.presets import FiveBarParams

from . import law
from .kinematics import Kinematics, no_assembly
from .model import DEFAULT_EXTENT, DEFAULT_GRID_STEP, ExactModel, TabulatedModel, perturbed_params
from .strategies import Strategy

SAMPLE_TIME = 1e-3
MODEL_KINDS = ("exact", "tabulated")
#: Where the exact model's terms come from: the compiled 5R kernel or the general algorithm.
KERNELS = ("fast", "general")
MEASUREMENTS = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2")
REFERENCES = ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")
OUTPUTS = ("tau1", "tau2", "i_ref1", "i_ref2", "e1", "e2")

_REFERENCE = "reference (x_d, y_d) = ({x_d!r}, {y_d!r}) m at t = {time:.6g} s"
_MEASURED = "measured (q1, q2) = ({q1!r}, {q2!r}) rad at t = {time:.6g} s: "
_POSE = "measured pose (x, y) = ({x:.6g}, {y:.6g}) m at t = {time:.6g} s: "
#: The law kernel's refusals (controller/law.py's codes): what they name and their messages.
REASONS = {
    law.NONFINITE: kernels.Reason("NONFINITE", MEASUREMENTS + REFERENCES, "",
                                  "input {variable} = {value!r} at t = {time:.6g} s is not finite"),
    law.REF_OUT: kernels.Reason("REF_OUT", ("(x_d, y_d)",) * 2, "m", _REFERENCE + " is outside the workspace"),
    law.REF_BAND: kernels.Reason("REF_BAND", ("margin",), "",
                                 _REFERENCE + " is in the near-singular band (margin {value:.3g} < {band:g})"),
    law.NO_ASSEMBLY: kernels.Reason("NO_ASSEMBLY", ("(q1, q2)",), "m", _MEASURED + "{detail}"),
    law.MEASURED_SINGULAR: kernels.Reason("MEASURED_SINGULAR", ("(q1, q2)",), "",
                                          _MEASURED + "a parallel singularity (det J_X = {value:.3g})"),
    law.REF_SINGULAR: kernels.Reason("REF_SINGULAR", ("(x_d, y_d)",), "",
                                     _REFERENCE + ": a chain is stretched or folded there (J_Theta singular)"),
    law.TABLE_OUT: kernels.Reason("TABLE_OUT", ("x", "y"), "m", _POSE + "{detail}"),
    law.TABLE_HOLE: kernels.Reason("TABLE_HOLE", ("x",), "m", _POSE + "{detail}"),
    law.EXACT_OUT: kernels.Reason("EXACT_OUT", ("(x, y)",), "m",
                                  _POSE + "point out of reach of a chain (distance {value:.6g} m)"),
    law.NONFINITE_OUTPUT: kernels.Reason(
        "NONFINITE_OUTPUT", OUTPUTS, "",
        "the law's outputs (tau1, tau2, i_ref1, i_ref2, e1, e2) = {outputs!r} at t = {time:.6g} s are not finite; "
        "largest input: {largest} = {largest_value!r}"),
}


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
    kernel : {"fast", "general"}
        Where the exact model's terms come from (:data:`KERNELS`, module docstring).
    table_fallback : bool
        Tabulated model: at a measured pose outside the table or in a cell with a left-out
        corner (near the workspace's edge or the singular band), evaluate the exact model
        there instead of refusing (counted in :attr:`fallbacks`).  The bench triangle's
        upper vertices (7.24) lie within 2.5 mm of the bench's reach.
    delay_compensation : (int, int)
        Periods of delay of the measured angles and of their rates before the commands take
        effect: the law acts on the joint state its model predicts for that time from the
        accelerations it commanded since (``kernels/src/law.h``; a per-component package at
        1 ms in a Jacobi master: (2, 3), docs/ssp.md).  (0, 0): the measurements as they are.

    Attributes
    ----------
    integral, k, s_prev, s, e : list of float
        The state of the law after the last sample (read only): the integral of
        k sat(s/phi), the sliding gains, s of the previous sample, s and the error e.
    compiled : bool
        True when a whole sample runs compiled (not with the general algorithm's terms).
    fallbacks : int
        Samples that used the exact model in place of the table (``table_fallback``).
    """

    #: Kernel buffers -> the function giving the words a run changes; a restored FMU state may
    #: not change the others (:mod:`fmus.slave.state`).
    KERNEL_BUFFERS = {"_buf": law.run_state_words}

    def __init__(self, params: FiveBarParams, strategy: Strategy, model="tabulated", model_error=0.0,
                 grid_step=DEFAULT_GRID_STEP, extent=DEFAULT_EXTENT, kt=None, T=SAMPLE_TIME,
                 band=fivebar.NEAR_SINGULAR_MARGIN, cache=True, kernel="fast", table_fallback=True,
                 delay_compensation=(0, 0)):
        if kernel not in KERNELS:
            raise ValueError(f"kernel = {kernel!r} is unknown; valid: {', '.join(KERNELS)}")
        _check_strategy(strategy)
        if model not in MODEL_KINDS:
            raise ValueError(f"model = {model!r} is unknown; valid: {', '.join(MODEL_KINDS)}")
        if not (math.isfinite(T) and T > 0.0):
            raise ValueError(f"T = {T!r} s must be > 0")
        self.delay_compensation = _check_compensation(delay_compensation)
        self.params, self.strategy, self.T, self.band = params.validate(), strategy, float(T), float(band)
        self.kin = Kinematics(params)
        self.kp, self.kv = strategy.lam ** 2, 2.0 * strategy.lam
        self.kt = default_kt() if kt is None else tuple(float(v) for v in kt)
        if not all(math.isfinite(v) and v > 0.0 for v in self.kt):
            raise ValueError(f"kt = {self.kt!r} must be > 0")
        self.model_kind = model if strategy.model_based else None
        self.model = self._fallback = None
        if strategy.model_based:
            model_params = perturbed_params(params, model_error)
            if model == "exact":
                self.model = ExactModel(model_params, kernel=kernel)
            else:
                self.model = TabulatedModel(model_params, grid_step, extent, cache=cache, band=band)
                if table_fallback:
                    self._fallback = ExactModel(model_params, kernel=kernel)
        self.fallbacks = 0
        self.kernel = kernel
        self.compiled = kernel == "fast"
        self._buf = law.pack(self.kin, self.band, strategy.space, self.model_kind, strategy.lam, strategy.phi,
                             strategy.gamma, strategy.m_star, self.kt, strategy.law, self.delay_compensation)
        self._scratch = np.zeros(law.SCRATCH_SIZE)
        self._terms = np.zeros(max(INVERSE_SIZE, law.TERMS_SIZE))   # inverse_terms writes all its words
        self.reset()

    def reset(self):
        """Zero the integral of the sliding term and restore the preset gains."""
        self._buf[:law.STATE_SIZE] = 0.0
        self._buf[law.STATE["k"]] = self.strategy.k

    # --- state (read only views as lists) ------------------------------------------------
    def _pair(self, field):
        return self._buf[law.STATE[field]].tolist()

    integral = property(lambda self: self._pair("integral"), doc="Integral of k sat(s/phi) (7.21).")
    k = property(lambda self: self._pair("k"), doc="Sliding gains (constant unless adaptive, 6.66).")
    s_prev = property(lambda self: self._pair("s_prev"), doc="s of the previous sample.")
    s = property(lambda self: self._pair("s"), doc="s of the last sample (7.22).")
    e = property(lambda self: self._pair("e"), doc="Error r_d - r of the last sample.")

    # --- the law ------------------------------------------------------------------------
    def step(self, t, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, dt=None):
        """One sample of the law (7.21-7.22): (tau1, tau2, i_ref1, i_ref2).

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
        kernels.Refused
            A ValueError naming the variable, its value and t: a non-finite input, a reference
            outside the workspace or in the near-singular band, a measured pose without
            assembly, a pose outside the tabulated model (without ``table_fallback``), outputs
            that are not finite.  The law's state is unchanged.
        """
        return self.step_with_errors(t, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, dt)[:4]

    def step_with_errors(self, t, q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d, dt=None):
        """:meth:`step` and the errors: (tau1, tau2, i_ref1, i_ref2, e1, e2)."""
        inputs = (q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d)
        h = self.T if dt is None else dt
        b = self._binding()
        code = b.sample(h, inputs)
        if code != law.OK:
            code = self._finish(b, code, h)
            if code != law.OK:
                raise self._refused(b.refusal, t, inputs)
        return tuple(b.outputs[:])

    def _binding(self):
        return law.binding(self, self._buf, self._scratch, self._terms,
                           self.model.kernel_table if self.model_kind == "tabulated" else None)

    def _finish(self, b, code, h):
        """The rest of a sample the kernel handed back: the exact model's terms (asked for, or
        off the table with ``table_fallback``), then the law; the final code."""
        if code == law.NEEDS_TERMS:
            self._exact_terms(self.model)
            return b.resume(h)
        if code not in law.TABLE_CODES or self._fallback is None:
            return code
        code = b.exact_pose()
        if code != law.OK:
            return code
        self._exact_terms(self._fallback)
        code = b.resume(h)
        self.fallbacks += code == law.OK
        return code

    def _exact_terms(self, model):
        """``model``'s M_M, v_M, g_M, Z (5.74-5.77) at the thesis' q, dq the kernel left in scratch."""
        q, dq = self._scratch[law.Q], self._scratch[law.DQ]
        if model.kernel == "fast":
            inverse_terms(model._p, q, dq, self._terms)
            return
        t = inverse_dynamics_terms(model.mechanism, q, dq)
        terms = self._terms
        terms[law.TERMS["M"]], terms[law.TERMS["v"]] = t.M.ravel(), t.v
        terms[law.TERMS["g"]], terms[law.TERMS["Z"]] = t.g, t.Z.ravel()

    def _refused(self, refusal, t, inputs) -> kernels.Refused:
        """The one record of a refused sample, with today's message texts."""
        q1, q2, x_d, y_d = inputs[0], inputs[1], inputs[6], inputs[7]
        x, y = self._scratch[law.POSE].tolist()
        code, detail = refusal.code, ""
        if code == law.NO_ASSEMBLY:
            detail = no_assembly(q1, q2, refusal.value)
        elif code in law.TABLE_CODES:
            detail = self.model.refusal_text(code, x, y)
        largest = max(range(len(inputs)), key=lambda i: abs(inputs[i]))
        return kernels.refused(REASONS, refusal, t, x_d=x_d, y_d=y_d, q1=q1, q2=q2, x=x, y=y, band=self.band,
                               detail=detail, outputs=tuple(self._scratch[law.OUT].tolist()),
                               largest=(MEASUREMENTS + REFERENCES)[largest], largest_value=inputs[largest])


def _check_compensation(value) -> tuple:
    """``delay_compensation`` as (int, int) in [0, law.MAX_PREDICT], or a ValueError naming it."""
    pair = tuple(value)
    if len(pair) != 2 or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                                 and 0 <= v <= law.MAX_PREDICT for v in pair):
        raise ValueError(f"delay_compensation = {value!r} must be two whole numbers of periods in "
                         f"[0, {law.MAX_PREDICT}] (angles, rates)")
    return int(pair[0]), int(pair[1])


def _check_strategy(strategy: Strategy) -> None:
    """Refuse a strategy the law cannot run, naming the parameter."""
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
