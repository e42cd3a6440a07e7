"""The bindings of the position law's C kernel (``kernels/src/law.c``; thesis 7.21-7.22).

The law, its checks, the kinematics and the tabulated model's interpolation run in C; this
module lays out the float64 buffers the kernel reads (offsets from the C structs through
:func:`kernels.layout`), binds the functions once, and turns a refusal code into the one
:class:`kernels.Refused` of :class:`controller.position.PositionController`.

A controller's buffers:

* ``buf``: ``pc_law_state`` (what a run changes, :func:`run_state_words`), then
  ``pc_law_params`` (gains, modes, geometry): :func:`pack`;
* ``scratch``: ``pc_law_scratch`` (inputs, outputs, the measured task state, the exact
  model's point);
* ``terms``: ``pc_law_terms`` (the exact model's M_M, v_M, g_M, Z), the first words of
  :data:`plant.fast5r.INVERSE_SIZE` so :func:`plant.fast5r.inverse_terms` fills it;
* the tabulated model's ``pc_law_table`` (:func:`pack_table`, held by the model).
"""
from __future__ import annotations

import ctypes
import weakref

import numpy as np

import kernels

PARAMS = kernels.layout("pc_law_params_fields")
STATE = kernels.layout("pc_law_state_fields")
TABLE = kernels.layout("pc_law_table_fields")
TERMS = kernels.layout("pc_law_terms_fields")
SCRATCH = kernels.layout("pc_law_scratch_fields")
TASK = kernels.layout("pc_5r_task_fields")

STATE_SIZE = kernels.size(STATE)
PARAMS_SIZE = kernels.size(PARAMS)
TERMS_SIZE = kernels.size(TERMS)
SCRATCH_SIZE = kernels.size(SCRATCH)
#: Entries of a table row (H00, H01, H11, cxx, cyy, cxy, g).
N_TERMS = 11
#: Most periods of delay the law predicts over (``PC_LAW_MAX_PREDICT``: the commanded
#: accelerations it keeps).
MAX_PREDICT = (STATE["past"].stop - STATE["past"].start) // 2

#: Where each field lies in a controller's ``buf`` (state first, then parameters).
BUF = {**STATE, **{name: slice(STATE_SIZE + s.start, STATE_SIZE + s.stop) for name, s in PARAMS.items()}}
#: Words of ``buf`` the FMU-state tests forge: a mode the kernel branches on, a gain, the integral.
BUF_MODEL, BUF_KP, BUF_INTEGRAL = BUF["model"].start, BUF["kp"].start, BUF["integral"].start
#: Where scratch holds the outputs (tau1, tau2, i_ref1, i_ref2, e1, e2), the measured pose and the
#: exact model's point.
OUT = SCRATCH["out"]
_TASK0 = SCRATCH["task"].start
POSE = slice(_TASK0 + TASK["x"].start, _TASK0 + TASK["y"].stop)
Q, DQ = SCRATCH["q"], SCRATCH["dq"]
#: Where scratch holds the joint state (q1, q2, dq1, dq2) the last sample acted on.
JOINT = SCRATCH["joint"]

SPACES = {"q": 0.0, "x": 1.0}
MODELS = {None: 0.0, "tabulated": 1.0, "exact": 2.0}
LAWS = {"unified": 0.0, "seed001": 1.0}

# Codes of law.h.
OK, NONFINITE, REF_OUT, REF_BAND, NO_ASSEMBLY, MEASURED_SINGULAR, REF_SINGULAR = 0, 1, 2, 3, 4, 5, 6
TABLE_OUT, TABLE_HOLE, EXACT_OUT, NONFINITE_OUTPUT, NEEDS_TERMS = 7, 8, 9, 10, 11
TABLE_CODES = (TABLE_OUT, TABLE_HOLE)


def run_state_words(buf):
    """The indices of ``buf`` a run changes (``pc_law_state``); every other word is
    configuration (modes, gains, the geometry), which a restored FMU state may not change
    (:mod:`fmus.slave.state`)."""
    return range(STATE_SIZE)


def pack(kin, band, space, model, lam, phi, gamma, m_star, kt, law="unified", predict=(0, 0)):
    """A controller's ``buf``: the state zero, then its parameters.

    Parameters
    ----------
    kin : controller.kinematics.Kinematics
    band : float
    space : {"q", "x"}
    model : {None, "tabulated", "exact"}
        None: the PD law.
    lam, phi, m_star : float
        kp = lam^2, kv = 2 lam (7.29-7.30).
    gamma : tuple or None
        Adaptation rates (6.66); None: constant gains.
    kt : (float, float)
    law : {"unified", "seed001"}
    predict : (int, int)
        Delay compensation: periods of delay of the angles and of the rates the law predicts
        over (``kernels/src/law.h``); (0, 0): none.
    """
    buf = np.zeros(STATE_SIZE + PARAMS_SIZE)
    buf[BUF["geometry"]] = (kin.l0, kin.l11, kin.l12, kin.l21, kin.l22)
    buf[BUF["band"]] = band
    buf[BUF["space"]], buf[BUF["model"]], buf[BUF["law"]] = SPACES[space], MODELS[model], LAWS[law]
    buf[BUF["kp"]], buf[BUF["kv"]], buf[BUF["lam"]], buf[BUF["phi"]] = lam ** 2, 2.0 * lam, lam, phi
    if gamma is not None:
        buf[BUF["adaptive"]] = 1.0
        buf[BUF["gamma"]] = gamma
    buf[BUF["m_star"]] = m_star
    buf[BUF["kt"]] = kt
    buf[BUF["predict"]] = predict
    return buf


def pack_table(x0, y0, step, table):
    """The ``pc_law_table`` of a grid from (x0, y0) with ``step`` and ``table`` of shape
    (ny + 1, nx + 1, N_TERMS) (NaN at left-out points)."""
    ny, nx = table.shape[0] - 1, table.shape[1] - 1
    first = TABLE["values"].start
    buf = np.empty(first + table.size)
    buf[TABLE["x0"]], buf[TABLE["y0"]], buf[TABLE["inv_step"]] = x0, y0, 1.0 / step
    buf[TABLE["nx"]], buf[TABLE["ny"]] = nx, ny
    buf[first:] = table.ravel()
    return buf


def table_values(buf, shape):
    """The table part of a ``pc_law_table`` buffer as an array of ``shape`` (a view)."""
    return buf[TABLE["values"].start:].reshape(shape)


_v, _d, _i = ctypes.c_void_p, ctypes.c_double, ctypes.c_int
_interpolate = kernels.function("pc_law_interpolate", _i, _v, _d, _d, _v, _v)
_run = kernels.function("pc_law_run", _i, _v, _d, _v)
_resume = kernels.function("pc_law_resume", _i, _v, _d, _v)
_exact_pose = kernels.function("pc_law_exact_pose", _i, _v, _v, _v)
_delay = kernels.function("pc_law_delay", None, _v, _i, _v)
_predict = kernels.function("pc_law_predict", None, _v, _v, _v, _i, _i, _d, _v)
#: ``pc_law_terms_fn``: the exact model's terms at (q, dq) into terms (model, q, dq, terms).
TERMS_FN = ctypes.CFUNCTYPE(None, _v, ctypes.POINTER(_d), ctypes.POINTER(_d), ctypes.POINTER(_d))


def delay(delayed, commands):
    """The computation delay (``pc_law_delay``): the commands to apply now, the oldest row of
    ``delayed`` (n rows of tau1, tau2, i_ref1, i_ref2), and ``commands`` queued as the newest,
    in place."""
    now = np.array(commands, dtype=np.float64)
    _delay(kernels.address(delayed), len(delayed), kernels.address(now))
    return tuple(now.tolist())


def predict(measured, past, bias, a, b, h):
    """``pc_law_predict``: the joint state (q1, q2, dq1, dq2) at the commands' time from
    ``measured`` angles ``a`` periods and rates ``b`` periods before it, ``past`` the joint
    accelerations commanded over the last max(a, b) periods (rows of 2, newest first) and
    ``bias`` the part of them the plant does not follow (rad/s^2), periods of ``h`` s."""
    m = np.ascontiguousarray(measured, dtype=np.float64)
    p = np.ascontiguousarray(past, dtype=np.float64).reshape(-1)
    o = np.ascontiguousarray(bias, dtype=np.float64)
    if m.shape != (4,) or o.shape != (2,) or len(p) < 2 * max(a, b):
        raise ValueError(f"predict: measured {m.shape}, bias {o.shape}, past of {len(p) // 2} rows for "
                         f"a = {a}, b = {b}: need 4, 2 and max(a, b) rows")
    joint = np.zeros(4)
    _predict(kernels.address(m), kernels.address(p) if len(p) else None, kernels.address(o), a, b, h,
             kernels.address(joint))
    return joint


def interpolate(table_buf, x, y, out):
    """The table's N_TERMS values at (x, y) into ``out`` (bilinear, 7.2.5); returns
    (code, refusal): :data:`OK`, :data:`TABLE_OUT` or :data:`TABLE_HOLE`."""
    refusal = kernels.Refusal()
    code = _interpolate(kernels.address(table_buf), x, y, kernels.address(out), ctypes.addressof(refusal))
    return code, refusal


class Context(ctypes.Structure):
    """``pc_law_context``: the addresses of one controller's buffers."""

    _fields_ = [("params", _v), ("table", _v), ("terms", _v), ("state", _v), ("scratch", _v),
                ("terms_of", _v), ("model", _v), ("delayed", _v), ("n_delayed", _i)]


class Binding:
    """One controller's context and refusal record, made once per set of buffers (the
    controller keeps no address: an FMU state restored over it must carry none)."""

    __slots__ = ("arrays", "context", "address", "refusal", "refusal_address", "inputs", "outputs", "_run")

    def __init__(self, buf, scratch, terms, table):
        self.arrays = (buf, scratch, terms, table)
        start = kernels.address(buf)
        self.context = Context(start + 8 * STATE_SIZE, None if table is None else kernels.address(table),
                               kernels.address(terms), start, kernels.address(scratch), None, None)
        self.address = ctypes.addressof(self.context)
        self.refusal = kernels.Refusal()
        self.refusal_address = ctypes.addressof(self.refusal)
        self._run = kernels.bind(_run, self.context, kernels.PER_CALL, self.refusal)   # run(h) -> the code
        # scratch's inputs and outputs as ctypes arrays: one slice copies them (numpy would convert each)
        first = kernels.address(scratch)
        self.inputs = (_d * 12).from_address(first + 8 * SCRATCH["in"].start)
        self.outputs = (_d * 6).from_address(first + 8 * OUT.start)

    def sample(self, h, inputs):
        """``pc_law_run`` on ``inputs`` (the 12 of ``pc_law_inputs``): the code; the outputs in
        :attr:`outputs`."""
        self.inputs[:] = inputs
        return self._run(h)

    def resume(self, h):
        """``pc_law_resume``: the rest of the sample with the terms in place."""
        return _resume(self.address, h, self.refusal_address)

    def exact_pose(self):
        """``pc_law_exact_pose``: the thesis' q, dq of the measured pose into scratch."""
        return _exact_pose(self.context.params, self.context.scratch, self.refusal_address)


def loop_context(b: Binding, delayed, terms_of=None) -> Context:
    """A context for ``pc_law_io`` in the compiled loop: ``b``'s buffers, the delay queue
    ``delayed`` (rows of 4) and the exact model's ``terms_of`` (a :data:`TERMS_FN`; the
    caller keeps it alive)."""
    context = Context.from_buffer_copy(b.context)
    if len(delayed):
        context.delayed, context.n_delayed = kernels.address(delayed), len(delayed)
    if terms_of is not None:
        context.terms_of = ctypes.cast(terms_of, _v)
    return context


#: id(owner) -> its Binding (removed when the owner goes).
_BINDINGS: dict = {}


def binding(owner, buf, scratch, terms, table) -> Binding:
    """The :class:`Binding` of ``owner``'s buffers, made on first use and again when a
    buffer was replaced."""
    b = _BINDINGS.get(id(owner))
    if b is None or not (b.arrays[0] is buf and b.arrays[1] is scratch and b.arrays[2] is terms
                         and b.arrays[3] is table):
        if b is None:
            weakref.finalize(owner, _BINDINGS.pop, id(owner), None)
        b = _BINDINGS[id(owner)] = Binding(buf, scratch, terms, table)
    return b
