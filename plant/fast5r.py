"""The 5R kernel's Python side: the C kernel ``kernels/src/fivebar.c`` bound through ctypes.

The kernel is the chapter 4-5 algorithm specialised to the thesis' 5R (Table 2 DH tables,
architecture 7.8-7.11) with scalars: per chain the tip, J_v and the velocity-quadratic tip term
(4.13, 4.57-4.58) and M, v, g of (4.85-4.87) with the rotor inertia (4.139-4.140); the forward
dynamics (5.56, 5.66, Baumgarte rows eliminated); the actuated 5R (the drives' armature
circuits, 4.162, and shaft torques, B.2, inside the ODE); the one RK4 (``pc_rk4.h``); the
report of a state, projection, residual and the inverse dynamics terms (5.67-5.77).

This module packs :class:`~plant.presets.FiveBarParams` into the C struct ``pc_fivebar_params``
(counter-masses, seed 001 (55)-(64), absorbed into each chain's links by
:func:`composite_link`), reads every buffer offset from the library (:func:`kernels.layout`),
and offers :class:`FastKernel`, the simulator's binding with its buffers' addresses computed
once.  ``tests/plant/test_plant_dynamics.py`` holds the kernel against the general algorithm
(:mod:`plant.serial`, :mod:`plant.parallel`), ``tests/kernels/test_kernels_fivebar.py`` checks energy,
refusals and layouts.
"""
from __future__ import annotations

import ctypes
import math

import numpy as np

import kernels

from .presets import ChainParams, FiveBarParams
from .serial import RigidLink, with_point_mass

_vp, _d, _i = ctypes.c_void_p, ctypes.c_double, ctypes.c_int


#: The C structs' fields: {name: slice of a float64 buffer} (kernels/src/fivebar.h).
PARAMS = kernels.layout("pc_fivebar_params_fields")
CHAIN = kernels.layout("pc_fivebar_chain_fields")
MOTOR = kernels.layout("pc_fivebar_motor_fields")
SETTINGS = kernels.layout("pc_fivebar_settings_fields")
REPORT = kernels.layout("pc_fivebar_report_fields")
INVERSE = kernels.layout("pc_fivebar_inverse_fields")
STATE = kernels.layout("pc_fivebar_state_fields")
PARAMS_SIZE, CHAIN_SIZE = kernels.size(PARAMS), kernels.size(CHAIN)
#: Columns of one motor row (``pc_fivebar_motor``): joint (0: q1, 1: q2), R, L, kt, ke, b, mu, omega_eps.
MOTOR_COLUMNS = kernels.size(MOTOR)
NO_MOTORS = np.empty((0, MOTOR_COLUMNS))
NO_VOLTAGES = np.empty(0)
#: Places in the report of a state (``pc_fivebar_report``): finite flag, residual norm (5.18), the
#: three singularity measures, then the outputs q1, q2, dq1, dq2, x, y, dx, dy, q1_enc, q2_enc.
REPORT_FINITE, REPORT_RESIDUAL = REPORT["finite"].start, REPORT["residual"].start
REPORT_MEASURES, REPORT_OUTPUTS, REPORT_SIZE = REPORT["measures"].start, REPORT["q1"].start, kernels.size(REPORT)
#: Places in the inverse dynamics terms (``pc_fivebar_inverse``): M_M, v_M, g_M, Z, c.
INVERSE_M, INVERSE_V, INVERSE_G = INVERSE["M"].start, INVERSE["v"].start, INVERSE["g"].start
INVERSE_Z, INVERSE_C, INVERSE_SIZE = INVERSE["Z"].start, INVERSE["c"].start, kernels.size(INVERSE)
#: Places in the settings (``pc_fivebar_settings``): Baumgarte lambda, RK4 steps per step, one
#: encoder count [rad], the largest residual and the smallest singularity measure accepted, the
#: encoders' zero errors [rad].
S_LAMBDA, S_SUBSTEPS, S_COUNT = SETTINGS["lambda"].start, SETTINGS["substeps"].start, SETTINGS["count"].start
S_RESIDUAL_STOP, S_SINGULAR_STOP = SETTINGS["residual_stop"].start, SETTINGS["singular_stop"].start
S_OFFSET1, S_OFFSET2, SETTINGS_SIZE = SETTINGS["offset"].start, SETTINGS["offset"].start + 1, kernels.size(SETTINGS)
#: Status codes of a step (fivebar.h's enum); on a refusal the state is unchanged.
OK, NONFINITE_INPUT, NONFINITE_STATE, DIVERGED, SINGULAR = 0, 1, 2, 3, 4
#: The plant's state entries before the currents (q and dq, 7.12).
PLANT_STATES = STATE["current"].start
#: Entries of x after the inputs: the FiveBarPlant outputs (fmus.slave.declarations.PLANT_OUTPUTS order).
PLANT_OUTPUT_COUNT = 11
#: The most motors a step takes (one per actuated joint).
MAX_MOTORS = 2


class Held(ctypes.Structure):
    """``pc_fivebar_held``: what a step holds constant (the actuated derivative's model)."""

    _fields_ = [("params", _vp), ("motors", _vp), ("voltages", _vp), ("u1", _d), ("u2", _d), ("lam", _d),
                ("n_motors", _i)]


class Context(ctypes.Structure):
    """``pc_fivebar_context``: the compiled loop's buffers of one plant (``pc_io_fn`` context)."""

    _fields_ = [("params", _vp), ("settings", _vp), ("motors", _vp), ("state", _vp), ("voltages", _vp),
                ("held", _vp), ("scratch", _vp), ("n_motors", _i), ("first", _i)]


_derivative = kernels.function("pc_fivebar_derivative", None, _vp, _vp, _d, _d, _d, _vp)
_actuated_derivative = kernels.function("pc_fivebar_actuated_derivative", None, _vp, _vp, _vp)
_advance = kernels.function("pc_fivebar_advance", None, _vp, _vp, _d, _i, _vp)
_residual = kernels.function("pc_fivebar_residual", None, _vp, _vp, _vp)
_report = kernels.function("pc_fivebar_report_of", None, _vp, _vp, _vp, _vp)
_step = kernels.function("pc_fivebar_step", _i, _vp, _vp, _vp, _i, _vp, _vp, _d, _d, _d, _vp, _vp, _vp)
_project = kernels.function("pc_fivebar_project", None, _vp, _vp, _i)
_inverse_terms = kernels.function("pc_fivebar_inverse_terms", None, _vp, _vp, _vp, _vp)
#: The compiled loop's I/O functions (``pc_io_fn``) with a :class:`Context`.
plant_io_c = kernels.function("pc_fivebar_plant_io", _i, _vp, _vp, _d, _d, _vp)
actuated_io_c = kernels.function("pc_fivebar_actuated_io", _i, _vp, _vp, _d, _d, _vp)
CONTEXT_SIZE = kernels.function("pc_fivebar_context_size", _i)()
#: Doubles of a step's scratch for up to :data:`MAX_MOTORS` motors, ``PC_FIVEBAR_SCRATCH`` of
#: fivebar.h: the trial state, RK4's work (5 n) and the last report's trigonometry
#: (``PC_FIVEBAR_TRIG_WORDS``), which must start zeroed.  Written out rather than asked of the
#: library, so that this side also drives an older build (benchmarks/bench_compiled_libs.py);
#: tests/kernels/test_kernels_fivebar.py holds it to ``pc_fivebar_scratch_words``.
SCRATCH_WORDS = 6 * (PLANT_STATES + MAX_MOTORS) + 17
#: The address of ``pc_fivebar_terms_of``: the inverse terms as the position law's terms function
#: (``pc_law_terms_fn``; its model a ``pc_fivebar_params`` buffer, its terms :data:`INVERSE_SIZE` words).
TERMS_OF = ctypes.cast(kernels.library().pc_fivebar_terms_of, _vp).value


def _address(array: np.ndarray) -> int:
    return kernels.address(array)


def composite_link(m: float, lg: float, Jz: float, mass: float, offset: float) -> tuple[float, float, float]:
    """(m, lg, Jz) of a planar link with a point ``mass`` on its line at ``offset`` from its
    proximal joint (:func:`plant.serial.with_point_mass`); unchanged, bit for bit, for mass 0."""
    link = with_point_mass(RigidLink(m, (lg, 0.0, 0.0), np.diag([0.0, Jz, Jz])), mass, (offset, 0.0, 0.0))
    return link.mass, link.com[0], link.inertia[2][2]


def _pack_chain(c: ChainParams, out: np.ndarray) -> None:
    """One ``pc_fivebar_chain`` into ``out``, the counter-masses absorbed into the links."""
    L1, L2 = c.counter_offsets()
    m1, lg1, Jz1 = composite_link(c.m1, c.lg1, c.Jz1, c.counter_mass1, L1)
    m2, lg2, Jz2 = composite_link(c.m2, c.lg2, c.Jz2, c.counter_mass2, L2)
    for name, value in (("l1", c.l1), ("l2", c.l2), ("lg1", lg1), ("lg2", lg2), ("m1", m1), ("m2", m2),
                        ("Jz1", Jz1), ("Jz2", Jz2), ("J_rotor", c.J_rotor)):
        out[CHAIN[name]] = value


def pack_params(params: FiveBarParams) -> np.ndarray:
    """The ``pc_fivebar_params`` buffer of ``params``."""
    p = np.zeros(PARAMS_SIZE)
    p[PARAMS["l0"]], p[PARAMS["m0"]], p[PARAMS["gravity"]] = params.l0, params.m0, params.gravity[:2]
    chains = p[PARAMS["chain"]]
    for k, c in enumerate((params.chain1, params.chain2)):
        _pack_chain(c, chains[k * CHAIN_SIZE:(k + 1) * CHAIN_SIZE])
    return p


def pack_settings(baumgarte: float, substeps: int, count: float, residual_stop: float, singular_stop: float,
                  offsets=(0.0, 0.0)) -> np.ndarray:
    """The ``pc_fivebar_settings`` buffer."""
    s = np.empty(SETTINGS_SIZE)
    s[S_LAMBDA], s[S_SUBSTEPS], s[S_COUNT] = baumgarte, substeps, count
    s[S_RESIDUAL_STOP], s[S_SINGULAR_STOP], s[SETTINGS["offset"]] = residual_stop, singular_stop, offsets
    return s


def _held(p, motors, voltages, u1, u2, lam) -> Held:
    return Held(_address(p), _address(motors), _address(voltages), u1, u2, lam, motors.shape[0])


# --- array-level calls (tests, the controller's exact model) -------------------------------------
def derivative(p, y, u1, u2, lam, out) -> None:
    """out = dy/dt for y = [q(7), dq(7)] with u* = (u1, u2) on theta11, theta21 (5.66)."""
    _derivative(_address(p), _address(y), u1, u2, lam, _address(out))


def actuated_derivative(p, motors, z, voltages, u1, u2, lam, out) -> None:
    """out = dz/dt for z = [q, dq, i_1 .. i_n]: the plant (5.66) with each motor's shaft torque
    (B.2) on its world joint besides (u1, u2) on theta11, theta21, and its armature circuit
    L di/dt = v_n - R i - ke omega (4.162); ``motors`` rows of :data:`MOTOR_COLUMNS`."""
    motors = np.ascontiguousarray(motors, dtype=np.float64)
    voltages = np.ascontiguousarray(voltages, dtype=np.float64)
    _actuated_derivative(ctypes.byref(_held(p, motors, voltages, u1, u2, lam)), _address(z), _address(out))


def report(p, y, count, offset1, offset2, out) -> None:
    """What the simulator checks and publishes after a step, for the state y (:data:`REPORT`)."""
    s = pack_settings(0.0, 1, count, 0.0, 0.0, (offset1, offset2))
    _report(_address(p), _address(s), _address(np.ascontiguousarray(y, dtype=np.float64)), _address(out))


def residual(p, y, out) -> None:
    """The position constraint residual q̄ (5.18, 7.7), 6 entries."""
    _residual(_address(p), _address(y), _address(out))


def project(p, y, iterations: int):
    """A copy of y put back on the constraints: Newton on the residual with x, y fixed, then
    dq = C dq# (as PlantSimulator.project)."""
    y = np.array(y, dtype=np.float64)
    _project(_address(p), _address(y), iterations)
    return y


def inverse_terms(p, q, dq, out) -> None:
    """The inverse dynamics terms of (5.67-5.77) at (q, dq) into ``out`` (:data:`INVERSE`), as
    :func:`plant.parallel.inverse_dynamics_terms`: ``M_M ddq# + v_M + g_M = Z^T u*`` (5.74),
    q# = (x, y); c (5.69) the chains' accelerations at ddq# = 0."""
    _inverse_terms(_address(p), _address(q), _address(dq), _address(out))


class FastKernel:
    """The C kernel bound to one parameter set and one set of step settings.

    The buffers (parameters, settings, report, scratch, refusal) belong to this object and
    their addresses are computed once, inside the bound calls.  A deep copy (an FMU snapshot)
    is this object: it holds configuration and scratch only, no run state, so an FMU state
    writes its class, not its buffers (``FMU_STATE_OPAQUE``, :func:`fmus.slave.state.opaque_tag`):
    a refused state cannot have written into them.
    """

    FMU_STATE_OPAQUE = True

    def __init__(self, params: FiveBarParams, settings: np.ndarray | None = None):
        self.p = pack_params(params)
        self.s = settings if settings is not None else pack_settings(0.0, 1, 1.0, math.inf, 0.0)
        self.report = np.empty(REPORT_SIZE)
        self.scratch = np.zeros(SCRATCH_WORDS)
        self.z = np.empty(PLANT_STATES + MAX_MOTORS)     # the state a step starts from
        self.voltages = np.zeros(MAX_MOTORS)
        self.refusal = kernels.Refusal()
        self._res = np.empty(6)
        self._bind()

    def _bind(self) -> None:
        """The kernel calls on this object's buffers (:func:`kernels.bind`: code, not state)."""
        self._steps = {}      # id(motor rows) -> (rows, the step bound to them)
        self._residual = kernels.bind(_residual, self.p, kernels.PER_CALL, self._res)
        self._derivative = kernels.bind(_derivative, self.p, *(kernels.PER_CALL,) * 5)

    def _bind_step(self, rows):
        """``pc_fivebar_step`` from ``self.z`` with the motor ``rows``, bound (once per array)."""
        known = self._steps[id(rows)] = (rows, kernels.bind(
            _step, self.p, self.s, rows, rows.shape[0], self.z, self.voltages, kernels.PER_CALL, kernels.PER_CALL,
            kernels.PER_CALL, self.scratch, self.report, self.refusal))
        return known

    def __deepcopy__(self, memo):
        return self

    def context(self, state, motors=NO_MOTORS, voltages=NO_VOLTAGES, held=None, first: int = 2) -> Context:
        """A ``pc_fivebar_context`` for the compiled loop over this kernel's parameters and
        settings, ``state`` (z), the motor rows, the ``voltages`` and ``held`` (u1, u2) buffers
        the caller fills, and a scratch of its own; the context keeps every buffer alive."""
        scratch = np.zeros(SCRATCH_WORDS)
        context = Context(_address(self.p), _address(self.s), _address(motors), _address(state),
                          _address(voltages) if voltages.size else None, None if held is None else _address(held),
                          _address(scratch), motors.shape[0], first)
        context.buffers = (self, state, motors, voltages, held, scratch)
        return context

    def derivative(self, y, u_star, baumgarte):
        """dy/dt (a new array) with u* on (theta11, theta21)."""
        y = np.ascontiguousarray(y, dtype=np.float64)
        out = np.empty(PLANT_STATES)
        self._derivative(_address(y), float(u_star[0]), float(u_star[1]), float(baumgarte), _address(out))
        return out

    def step(self, z, u1: float, u2: float, dt: float, motors=NO_MOTORS, voltages=NO_VOLTAGES) -> int:
        """RK4 from ``z`` (copied into ``self.z``, ``voltages`` into ``self.voltages``) over dt
        with the settings; returns the status (:data:`OK` or a
        refusal code, ``self.refusal`` naming the quantity).  The trial state is
        ``self.scratch[:z.size]`` and its report ``self.report``; ``z`` is not changed."""
        n = z.size
        self.z[:n] = z
        if n > PLANT_STATES:
            self.voltages[:n - PLANT_STATES] = voltages
        known = self._steps.get(id(motors))
        if known is None or known[0] is not motors:
            known = self._bind_step(motors)
        return known[1](u1, u2, dt)

    def advance(self, z, u1, u2, baumgarte, dt, substeps, motors=NO_MOTORS, voltages=NO_VOLTAGES):
        """RK4 of the actuated derivative from z over dt (a new array), no checks."""
        z = np.array(z, dtype=np.float64)
        held = _held(self.p, motors, voltages, float(u1), float(u2), float(baumgarte))
        _advance(ctypes.byref(held), _address(z), float(dt), int(substeps), _address(self.scratch))
        return z

    def actuated_derivative(self, z, motors, voltages, u1, u2, baumgarte):
        """dz/dt (a new array) of :func:`actuated_derivative`."""
        out = np.empty(len(z))
        actuated_derivative(self.p, motors, np.ascontiguousarray(z, dtype=np.float64), voltages, float(u1),
                            float(u2), float(baumgarte), out)
        return out

    def project(self, y, iterations=3):
        return project(self.p, y, iterations)

    def residual_norm(self, y) -> float:
        self._residual(_address(np.ascontiguousarray(y, dtype=np.float64)))
        return math.sqrt(float(self._res @ self._res))

    def residual(self, y):
        self._residual(_address(np.ascontiguousarray(y, dtype=np.float64)))
        return self._res.copy()
