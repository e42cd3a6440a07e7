"""Numerical derivators of the encoder angles (thesis section 7.2.3).

The velocity estimate is the backward difference (7.19)

    v_k = (q_k - q_{k-1}) / T

in series with a 2nd-order Bessel low-pass F_v; the acceleration estimate is the
backward difference of that (filtered) velocity in series with an 8th-order Bessel
low-pass F_a:

    V(z) = F_v(z) (1 - z^-1)/T Q(z),       A(z) = F_a(z) (1 - z^-1)/T V(z).

Design and discretisation
-------------------------
Each low-pass is the analog Bessel prototype ``scipy.signal.bessel(order, Wa,
analog=True, norm='mag')`` (so ``fc`` is the -3 dB frequency), discretised with the
bilinear (Tustin) transform prewarped at ``fc``: ``Wa = (2/T) tan(pi fc T)``. Why
bilinear rather than zero-order-hold or matched poles:

* it maps s = 0 to z = 1, so the unit DC gain, on which the exactness below rests,
  is kept by construction (each second-order section is then renormalised to
  sum(b) = sum(a) so that rounding of the coefficients does not spoil it);
* it puts every filter zero at z = -1, i.e. infinite attenuation at the Nyquist
  frequency, exactly where the backward difference amplifies encoder quantisation
  noise most (|1 - z^-1| = 2);
* with prewarping, the -3 dB point stays at ``fc``; the warping shortens the DC group
  delay of the default filters by only 3.3 % (velocity) and 0.5 % (acceleration)
  with respect to analog Bessel filters of the same -3 dB frequency.

The filters are stored as second-order sections (no high-order polynomial is ever
formed); a step runs the chain (difference, F_v's sections, difference, F_a's sections)
as that cascade, each section in direct form II transposed: the C kernel
``pc_derivator_step`` (``kernels/src/derivator.c``), whose state words are those of the
chain's state-space model built section by section here (:func:`_differentiator_ss`, for
linear analyses and as the tests' independent formulation).

Exactness
---------
With unit-DC-gain filters, a polynomial input leaves, after the transient, a
polynomial delayed by the DC group delay:

* for q of degree <= 2, v_k = dq/dt(t_k - ``velocity_delay``) with
  ``velocity_delay = T/2 + tau_v``; in particular v_k is the exact slope of a ramp;
* for q of degree <= 3, a_k = d2q/dt2(t_k - ``acceleration_delay``) with
  ``acceleration_delay = T + tau_v + tau_a``; in particular a_k is the exact
  curvature of a parabola,

where tau_v, tau_a are the DC group delays of F_v, F_a. "After the transient"
means: the transient decays as the slowest filter pole (radius 0.81 for F_a at the
default 40 Hz). With the default cut-offs, from a start at rest (:meth:`Derivator.reset`)
the velocity of a ramp is within 1e-9 (relative to the slope) of the slope from
sample 31 on, the acceleration of a parabola within 1e-9 (relative) of its
curvature from sample 96 on, and the acceleration of a ramp below 1e-9 x slope/s
from sample 129 on; past that only rounding remains (below 2e-11 relative for
angles of a few rad).
``tests/controller/test_derivators.py`` checks these from sample 150.

Default cut-offs (measured numbers: ``docs/derivators.md``)
-----------------------------------------------------------
``fc_vel = 100 Hz``. The position loops have lambda up to 70 rad/s; the loop
(lambda^2 + 2 lambda s)/s^2 then crosses over at about 24 Hz with 76 deg of phase
margin if the velocity were ideal. The velocity estimate lags by
``velocity_delay`` = 2.6 ms (10 deg at 11 Hz, 4.7 deg at 5 Hz); with it and the
zero-order hold the margin is 52 deg (43 deg with a further one-step computation
delay). A lower fc_vel costs margin fast (60 Hz: 40 deg); a higher one lets the
quantisation noise through: at 100 Hz, white quantisation noise of one count
(2 pi/20000 rad, variance step^2/12) gives 0.023 rad/s rms of velocity, against
0.128 rad/s for the bare difference. At lambda = 70 rad/s, kv = 2 lambda times it is
3.2 rad/s^2, against 1.5 rad/s^2 for kp = lambda^2 times one count: the velocity
feedback stays within a factor 2 of the quantisation the position feedback sees
anyway.

``fc_acc = 40 Hz``. The acceleration enters only the sliding-mode term
integral(k sat(s/phi)) (7.21-7.22), where it is integrated, so its lag matters less
than its noise: quantisation must not drive s across the boundary layer, whose
smallest width in joint space is phi = 20 rad/s^2 (Tables 6-7). At 40 Hz the
noise is 1.5 rad/s^2 rms (< phi/10; 50 Hz gives 2.4), for a lag of
``acceleration_delay`` = 15.7 ms (28 deg at 5 Hz, 62 deg at 11 Hz; 5.6 deg at the
1 Hz of the thesis' circle).
"""

import ctypes
import math
import weakref

import numpy as np

import kernels

from . import fastderivator

SAMPLE_TIME = 1e-3
"""Sample time of the bench's controller, s (thesis 7.2.10)."""

VELOCITY_FILTER_ORDER = 2
ACCELERATION_FILTER_ORDER = 8
DEFAULT_FC_VEL = 100.0
"""Default -3 dB frequency of the velocity low-pass, Hz."""
DEFAULT_FC_ACC = 40.0
"""Default -3 dB frequency of the acceleration low-pass, Hz."""


def bessel_lowpass_sos(order, fc, T=SAMPLE_TIME):
    """Discrete Bessel low-pass with unit DC gain, as second-order sections.

    Parameters
    ----------
    order : int
        Filter order.
    fc : float
        -3 dB frequency in Hz, 0 < fc < 1/(2T).
    T : float
        Sample time in s.

    Returns
    -------
    numpy.ndarray
        Second-order sections, shape (ceil(order/2), 6), rows [b0 b1 b2 1 a1 a2],
        each section with sum(b) = sum(a) (unit DC gain).
    """
    if not 0.0 < fc < 0.5 / T:
        raise ValueError(f"cut-off {fc} Hz must lie in (0, {0.5 / T}) Hz for T = {T} s")
    key = ("bessel_lowpass_sos", int(order), float(fc), float(T))
    if key in PRECOMPUTED:
        return PRECOMPUTED[key].copy()
    from scipy import signal   # here, not at import: it takes about 1 s (an FMU's start, issue 27)

    prewarped = 2.0 / T * np.tan(np.pi * fc * T)
    zeros, poles, gain = signal.bessel(order, prewarped, analog=True, norm="mag", output="zpk")
    sos = signal.zpk2sos(*signal.bilinear_zpk(zeros, poles, gain, fs=1.0 / T))
    sos[:, :3] *= (sos[:, 3:].sum(axis=1) / sos[:, :3].sum(axis=1))[:, None]
    if RECORDING:
        PRECOMPUTED[key] = sos.copy()
    return sos


#: Filters computed ahead, ``("bessel_lowpass_sos", order, fc, T)`` -> sos: an FMU's, computed
#: when it was built for its parameters then and loaded from its resources
#: (:mod:`fmus.slave.designs`), so that starting it needs no scipy.signal.  While an FMU is built
#: (``RECORDING``), each filter computed is added.
PRECOMPUTED = {}
RECORDING = False


def dc_group_delay(sos, T=SAMPLE_TIME):
    """Group delay at zero frequency of a filter in second-order sections, s.

    For H(z) = sum b_n z^-n / sum a_n z^-n it is
    sum n b_n / sum b_n - sum n a_n / sum a_n samples, summed over sections.
    """
    taps = np.arange(3)
    numerator, denominator = sos[:, :3], sos[:, 3:]
    samples = taps @ numerator.T / numerator.sum(axis=1) - taps @ denominator.T / denominator.sum(axis=1)
    return float(samples.sum() * T)


def _backward_difference_ss(T):
    """State space of (1 - z^-1)/T; the state is the previous input."""
    return np.zeros((1, 1)), np.ones((1, 1)), np.full((1, 1), -1.0 / T), np.full((1, 1), 1.0 / T)


def _section_ss(section):
    """State space (direct form II transposed) of one second-order section."""
    b0, b1, b2, _, a1, a2 = section
    return (
        np.array([[-a1, 1.0], [-a2, 0.0]]),
        np.array([[b1 - a1 * b0], [b2 - a2 * b0]]),
        np.array([[1.0, 0.0]]),
        np.array([[b0]]),
    )


def _series(first, second):
    """State space of ``second`` driven by the output of ``first`` (states of first first)."""
    a1, b1, c1, d1 = first
    a2, b2, c2, d2 = second
    return (
        np.block([[a1, np.zeros((a1.shape[0], a2.shape[1]))], [b2 @ c1, a2]]),
        np.vstack([b1, b2 @ d1]),
        np.hstack([d2 @ c1, c2]),
        d2 @ d1,
    )


def _differentiator_ss(sos, T, upstream=None):
    """Backward difference then the sections of ``sos``, after ``upstream`` if given: (A, B, C, D),
    the states in the order of the C kernel's state words (``kernels/src/derivator.h``)."""
    system = _backward_difference_ss(T) if upstream is None else _series(upstream, _backward_difference_ss(T))
    for section in sos:
        system = _series(system, _section_ss(section))
    return system


class Derivator:
    """Velocity and acceleration estimates of sampled angles (thesis 7.2.3).

    Parameters
    ----------
    fc_vel : float
        -3 dB frequency of the 2nd-order Bessel velocity low-pass, Hz.
    fc_acc : float
        -3 dB frequency of the 8th-order Bessel acceleration low-pass, Hz.
    T : float
        Sample time, s.

    Attributes
    ----------
    velocity_sos, acceleration_sos : numpy.ndarray
        The two low-passes F_v, F_a as second-order sections.
    velocity_delay, acceleration_delay : float
        Steady-state delays, s, of the estimates on polynomial inputs (module docstring).

    Notes
    -----
    Call :meth:`reset` before the first :meth:`step`; it fixes the number of channels.
    """

    #: Kernel buffers -> the function giving the words a run changes; a restored FMU state may
    #: not change the others (:mod:`fmus.slave.state`).
    KERNEL_BUFFERS = {"buf": fastderivator.run_state_words}

    def __init__(self, fc_vel=DEFAULT_FC_VEL, fc_acc=DEFAULT_FC_ACC, T=SAMPLE_TIME):
        self.fc_vel, self.fc_acc, self.T = float(fc_vel), float(fc_acc), float(T)
        self.velocity_sos = bessel_lowpass_sos(VELOCITY_FILTER_ORDER, fc_vel, T)
        self.acceleration_sos = bessel_lowpass_sos(ACCELERATION_FILTER_ORDER, fc_acc, T)
        velocity_filter_delay = dc_group_delay(self.velocity_sos, T)
        self.velocity_delay = T / 2 + velocity_filter_delay
        self.acceleration_delay = T + velocity_filter_delay + dc_group_delay(self.acceleration_sos, T)

        self.buf = None

    def reset(self, q0):
        """Start at rest at the angles ``q0`` (one per channel): both estimates are zero.

        Parameters
        ----------
        q0 : array_like
            Initial angles, rad; their number sets the number of channels.
        """
        q0 = np.atleast_1d(np.asarray(q0, dtype=float))
        self.start_at_first_sample(q0.size)
        self._rest_at(q0)

    def start_at_first_sample(self, channels):
        """Start at rest at the angles of the first :meth:`step` (``channels`` of them)."""
        self.buf = fastderivator.pack(self.T, self.velocity_sos, self.acceleration_sos, int(channels))

    def _rest_at(self, q0):
        """At rest at q0 (``pc_derivator_reset``)."""
        call, angles = _call(self), np.ascontiguousarray(q0, dtype=float)
        if _RESET(call.context, kernels.address(angles), call.refusal) != 0:
            raise kernels.refused(_REASONS, call.refusal, angles=q0.tolist(), limit=math.inf, words=call.buf.size)

    def step(self, q, limit=math.inf):
        """Take the angles of the current sample and return the estimates.

        One call of the C kernel ``pc_derivator_step`` on :attr:`buf` (the array the FMU
        state saves and the compiled loop reads).

        Parameters
        ----------
        q : array_like
            Angles q_k, rad, one per channel.
        limit : float
            Largest |q| accepted, rad.

        Returns
        -------
        dq, ddq : numpy.ndarray
            Velocity (rad/s) and acceleration (rad/s^2) estimates at sample k; when not
            finite, the state is not advanced.

        Raises
        ------
        kernels.Refused
            (a ValueError) An angle not finite or beyond ``limit``, or a buffer whose sizes do
            not fit it; the state is not advanced.
        """
        call = self._advance(q, limit)
        m = call.q.size
        return call.out[:m].copy(), call.out[m:].copy()

    def step_values(self, q, limit=math.inf) -> list:
        """:meth:`step`'s estimates as one list of floats, the velocities then the
        accelerations (no arrays built: an FMU's doStep)."""
        return self._advance(q, limit).out.tolist()

    def _advance(self, q, limit):
        """One ``pc_derivator_step`` (see :meth:`step`); the call whose ``out`` holds the estimates."""
        if self.buf is None:
            raise RuntimeError("Derivator.step called before reset(q0)")
        call = _call(self)
        if call.scratch.size:       # else the buffer is damaged: refused before q is read
            try:
                call.q_values[:] = q
            except (TypeError, ValueError):   # not floats, or not of the right length:
                call.q[:] = q                 # numpy's conversion, or its error, as ever
        code = call.step(limit)
        if code not in (fastderivator.OK, fastderivator.NONFINITE_OUTPUT):
            raise kernels.refused(_REASONS, call.refusal, angles=call.q.tolist(), limit=limit, words=call.buf.size)
        return call

    def frequency_response(self, f):
        """Frequency responses of the velocity and acceleration estimates.

        Parameters
        ----------
        f : array_like
            Frequencies, Hz (below 1/(2T)).

        Returns
        -------
        velocity, acceleration : numpy.ndarray
            Complex gains from q to dq and to ddq; an ideal derivator has
            j 2 pi f and -(2 pi f)^2.
        """
        from scipy import signal

        omega = 2 * np.pi * np.asarray(f, dtype=float) * self.T
        difference = 2j * np.sin(omega / 2) * np.exp(-0.5j * omega) / self.T  # (1 - z^-1)/T, no cancellation
        _, velocity_filter = signal.sosfreqz(self.velocity_sos, worN=omega)
        _, acceleration_filter = signal.sosfreqz(self.acceleration_sos, worN=omega)
        velocity = difference * velocity_filter
        return velocity, difference * acceleration_filter * velocity


# --- the C kernel -------------------------------------------------------------------------------

class _Context(ctypes.Structure):
    """``pc_derivator_context``."""

    _fields_ = [("derivator", ctypes.c_void_p), ("scratch", ctypes.c_void_p), ("words", ctypes.c_long),
                ("scratch_words", ctypes.c_long), ("limit", ctypes.c_double)]


_CONTEXT_P, _REFUSAL_P = ctypes.POINTER(_Context), ctypes.POINTER(kernels.Refusal)
_STEP = kernels.function("pc_derivator_step", ctypes.c_int, _CONTEXT_P, ctypes.c_void_p, ctypes.c_double,
                         ctypes.c_void_p, _REFUSAL_P)
_RESET = kernels.function("pc_derivator_reset", ctypes.c_int, _CONTEXT_P, ctypes.c_void_p, _REFUSAL_P)
_SCRATCH_WORDS = kernels.function("pc_derivator_scratch_words", ctypes.c_long, ctypes.c_void_p, ctypes.c_long)
_LAYOUT_WORDS = ("states", "channels", "length", "scratch length", "velocity sections")
_REASONS = {
    fastderivator.BAD_INPUT: kernels.Reason("bad_input", ("q1", "q2"), "rad",
                                            "angles q = {angles!r} rad must be finite with |q| <= {limit:g}"),
    fastderivator.BAD_LAYOUT: kernels.Reason(
        "bad_layout", _LAYOUT_WORDS, "",
        "the derivator's buffer of {words} words is damaged: {variable} = {value!r} does not fit it"),
}


class _Call:
    """What a :class:`Derivator`'s kernel calls need besides its buffer: the context (the
    buffers' addresses), the input, output and scratch arrays and the refusal record.  Kept
    out of the Derivator (whose attributes are its FMU state), in :data:`_CALLS`."""

    __slots__ = ("buf", "q", "q_values", "out", "scratch", "context", "refusal", "step")

    def __init__(self, buf):
        # Sized by the kernel's own check of the buffer: none for sizes that do not fit it
        # (a damaged buffer, which every kernel call then refuses).
        self.scratch = np.zeros(_SCRATCH_WORDS(kernels.address(buf), buf.size))
        channels = int(buf[fastderivator.V_CHANNELS]) if self.scratch.size else 1
        self.buf, self.q, self.out = buf, np.zeros(channels), np.zeros(2 * channels)
        #: ``q`` as a ctypes array: a short tuple goes in about three times faster than through numpy
        self.q_values = (ctypes.c_double * channels).from_buffer(self.q)
        self.context = _Context(kernels.address(buf), kernels.address(self.scratch), buf.size, self.scratch.size,
                                math.inf)
        self.refusal = kernels.Refusal()
        #: step(limit) -> the code: ``pc_derivator_step`` from ``q`` into ``out`` (:func:`kernels.bind`)
        self.step = kernels.bind(_STEP, self.context, self.q, kernels.PER_CALL, self.out, self.refusal)


def kernel_context(derivator, limit: float) -> _Context:
    """A ``pc_derivator_context`` over ``derivator.buf`` (started or not) with its own scratch
    and ``limit`` [rad], for ``pc_derivator_io`` in the compiled loop; the caller keeps it alive
    (it keeps its scratch)."""
    call = _Call(derivator.buf)
    call.context.limit = limit
    call.context.keep = call
    return call.context


#: Derivator -> its :class:`_Call`, rebuilt when its buffer is another array (a restored state).
_CALLS = weakref.WeakKeyDictionary()


def _call(derivator) -> _Call:
    call = _CALLS.get(derivator)
    if call is None or call.buf is not derivator.buf:
        call = _CALLS[derivator] = _Call(derivator.buf)
    return call
