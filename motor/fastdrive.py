"""Compiled per-step arithmetic of the DC drive and the current observer (4.162, B.2, app. C, 7.20).

Also the bench's imperfections a drive can model (all off by default): the PWM's voltage
resolution, the offset and the noise of the current its loop reads (a stateless
:func:`gaussian` of seed, instance and sample), and a friction torque given from outside
(:func:`drive_step_friction`: the LuGre model of :mod:`motor.friction`, called beside, not
from, this file).

Design-time work stays in Python (:mod:`motor.current_controller` places the poles with
python-control, :mod:`motor.electrics` computes the step coefficients (a, g) and the mean
weights for a step length); what runs every step is here, compiled with numba, and called
by :class:`motor.Drive`, :class:`motor.CurrentController`, :class:`motor.CurrentObserver`
(so by the FMU slaves, the in-process master and the reference) and by the compiled scene
loop (:mod:`fmus.compiled`).

Each model keeps its constants and its state in one float64 array with the named layout
below.  A kernel returns a status first: :data:`OK`, or a refusal code, in which case it
has changed NOTHING and the Python caller raises the message (naming the input, its value
and the time).  Every expression is written in the order of the Python it replaced, so the
results are bit-identical to it (``tests/test_fastdrive.py``).

This module calls no compiled function of another file, so numba's on-disk cache
(``cache=True``, invalidated by this file's modification time only) cannot go stale.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

# --- status codes ------------------------------------------------------------------------
OK = 0
#: An input is NaN or infinite.
NONFINITE_INPUT = 1
#: The step length is not the one the coefficients were computed for (Python prepares it).
UNPREPARED_STEP = 2
#: The current or torque after the step is not finite.
DIVERGED = 3

# --- layout of a current controller's array (CurrentController, K(z) of C.5) ----------------
C_ALPHA, C_BETA, C_GAMMA, C_DELTA, C_VMAX = 0, 1, 2, 3, 4
#: State: the last two saturated outputs u and errors e.
C_U1, C_U2, C_E1, C_E2 = 5, 6, 7, 8
CONTROLLER_SIZE = 9

# --- layout of a drive's array (Drive) -------------------------------------------------------
D_CURRENT_MODE = 0       # 1: current mode (K(z) on i_ref, i_hat), 0: voltage mode (v_ref)
D_MEAN_TORQUE = 1        # 1: torque_output "mean", 0: "end"
D_KE, D_KT, D_B, D_MU, D_OMEGA_EPS, D_VMAX, D_T = 2, 3, 4, 5, 6, 7, 8
#: The step length h the coefficients are for, a and g of i(t+h) = a i + g (v - ke omega),
#: the mean weights w_i, w_u (motor.electrics), and h / T.
D_H, D_A, D_G, D_WI, D_WU, D_PHASE_STEP = 9, 10, 11, 12, 13, 14
#: State: armature current i [A], last applied voltage v [V], controller phase (fraction of T).
D_I, D_V, D_PHASE = 15, 16, 17
#: The bench's imperfections (0: ideal): the PWM's voltage quantum v_max / pwm_counts [V]; the
#: offset [A] and the noise's standard deviation [A] of the current the loop reads, the
#: noise's seed and instance (:func:`gaussian`); state: the controller samples taken so far.
D_PWM_QUANTUM, D_I_OFFSET, D_I_NOISE, D_NOISE_SEED, D_NOISE_INSTANCE, D_SAMPLE = 18, 19, 20, 21, 22, 23
DRIVE_SIZE = 24

#: Relative tolerance deciding that a controller period is over (motor.drive._PHASE_TOL).
PHASE_TOL = 1e-6

# --- layout of an observer's array (CurrentObserver) ----------------------------------------
O_STATIC = 0             # 1: static kind (7.20), 0: dynamic
O_KE, O_H, O_A, O_G = 1, 2, 3, 4
#: State: the estimate, the speed of the previous call and whether there was one.
O_I_HAT, O_OMEGA_PREV, O_HAS_PREV = 5, 6, 7
OBSERVER_SIZE = 8


def new_controller(alpha, beta, gamma, delta, v_max) -> np.ndarray:
    """A current controller's array, state zero."""
    c = np.zeros(CONTROLLER_SIZE)
    c[C_ALPHA], c[C_BETA], c[C_GAMMA], c[C_DELTA], c[C_VMAX] = alpha, beta, gamma, delta, v_max
    return c


@njit(cache=True)
def _saturate(v, v_max):
    return min(max(v, -v_max), v_max)


@njit(cache=True)
def _controller_output(c, e):
    """K(z) as the anti-windup difference equation (app. C): the saturated voltage for error e."""
    v = ((1.0 + c[C_DELTA]) * c[C_U1] - c[C_DELTA] * c[C_U2]
         + c[C_ALPHA] * e + c[C_BETA] * c[C_E1] + c[C_GAMMA] * c[C_E2])
    return _saturate(v, c[C_VMAX])


@njit(cache=True)
def _controller_commit(c, v, e):
    c[C_U2] = c[C_U1]
    c[C_U1] = v
    c[C_E2] = c[C_E1]
    c[C_E1] = e


@njit(cache=True)
def controller_update(c, i_ref, i_meas):
    """One sample of K(z): the voltage to hold over the next period (state advanced)."""
    e = i_ref - i_meas
    v = _controller_output(c, e)
    _controller_commit(c, v, e)
    return v


@njit(cache=True)
def shaft_torque(d, i, omega):
    """kt i - b omega - mu tanh(omega / omega_eps) (B.2, B.3; motor.electrics.shaft_torque)."""
    return d[D_KT] * i - d[D_B] * omega - d[D_MU] * math.tanh(omega / d[D_OMEGA_EPS])


# --- the bench's imperfections: a stateless noise, the PWM's quantum --------------------------
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


@njit(cache=True)
def _splitmix64(x):
    """One output of SplitMix64 (Steele, Lea, Flood 2014) for the state x (uint64)."""
    z = x + _GOLDEN
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@njit(cache=True)
def _unit(x):
    """A uint64's top 53 bits as a float in (0, 1]."""
    return (float(x >> np.uint64(11)) + 1.0) * (1.0 / 9007199254740992.0)


@njit(cache=True)
def _key(seed, instance, step):
    """SplitMix64 chained over (seed, instance, step), integers >= 0."""
    return _splitmix64(_splitmix64(_splitmix64(np.uint64(seed)) ^ np.uint64(instance)) ^ np.uint64(step))


@njit(cache=True)
def uniform(seed, instance, step):
    """A uniform sample in (0, 1] that depends only on (seed, instance, step), integers >= 0
    (the first uniform :func:`gaussian` draws for the same three)."""
    return _unit(_key(seed, instance, step))


@njit(cache=True)
def gaussian(seed, instance, step):
    """A standard normal sample that depends only on (seed, instance, step), integers >= 0:
    SplitMix64 hashes them, Box-Muller turns two 53-bit uniforms into the sample.  No state:
    a rerun, or a restored FMU state, draws the same noise."""
    key = _key(seed, instance, step)
    u1 = _unit(key)
    u2 = _unit(_splitmix64(key))
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@njit(cache=True)
def _measured_current(d, i_hat):
    """The current the loop reads at this sample: i_hat plus the offset and the noise (if any)."""
    if d[D_I_OFFSET] == 0.0 and d[D_I_NOISE] == 0.0:
        return i_hat
    noise = d[D_I_NOISE] * gaussian(int(d[D_NOISE_SEED]), int(d[D_NOISE_INSTANCE]), int(d[D_SAMPLE]))
    return i_hat + d[D_I_OFFSET] + noise


@njit(cache=True)
def _applied(d, v):
    """v as the PWM applies it: the nearest multiple of the quantum (ties away from 0)."""
    q = d[D_PWM_QUANTUM]
    if q == 0.0:
        return v
    return math.copysign(math.floor(abs(v) / q + 0.5) * q, v)


@njit(cache=True)
def _voltage(d, c, i_ref, v_ref, i_hat):
    """(v, e, sampled, next phase) of this step, nothing changed."""
    if d[D_CURRENT_MODE] == 0.0:
        return _applied(d, _saturate(v_ref, d[D_VMAX])), 0.0, False, d[D_PHASE]
    sampled = d[D_PHASE] == 0.0
    e = i_ref - (_measured_current(d, i_hat) if sampled else i_hat)
    v = _applied(d, _controller_output(c, e)) if sampled else d[D_V]
    phase = d[D_PHASE] + d[D_PHASE_STEP]
    if phase > 1.0 - PHASE_TOL:
        phase = 0.0
    return v, e, sampled, phase


@njit(cache=True)
def _commit_voltage(d, c, v, e, sampled, phase):
    if sampled:
        # The controller remembers its own output; the PWM quantises only what is applied.
        _controller_commit(c, v if d[D_PWM_QUANTUM] == 0.0 else _controller_output(c, e), e)
        d[D_SAMPLE] += 1.0
    d[D_PHASE] = phase


@njit(cache=True)
def peek_voltage(d, c, i_ref, v_ref, i_hat, h):
    """(status, v, e, sampled, phase): :func:`sample_voltage` without changing anything;
    :func:`commit_step` keeps it (a plant that integrates the current, fmus.compiled)."""
    if not (math.isfinite(i_ref) and math.isfinite(v_ref) and math.isfinite(i_hat)):
        return NONFINITE_INPUT, 0.0, 0.0, False, 0.0
    if h != d[D_H]:
        return UNPREPARED_STEP, 0.0, 0.0, False, 0.0
    v, e, sampled, phase = _voltage(d, c, i_ref, v_ref, i_hat)
    return OK, v, e, sampled, phase


@njit(cache=True)
def commit_step(d, c, v, e, sampled, phase, i):
    """Keep the sample of :func:`peek_voltage` and the current i at the step's end."""
    _commit_voltage(d, c, v, e, sampled, phase)
    d[D_I] = i
    d[D_V] = v


@njit(cache=True)
def sample_voltage(d, c, i_ref, v_ref, i_hat, h):
    """(status, v): the voltage held over the next step of length h (Drive.sample_voltage).

    Current mode: a new controller sample at the start of each period T, else the held
    voltage; voltage mode: v_ref saturated.  Advances the controller and the phase.
    """
    status, v, e, sampled, phase = peek_voltage(d, c, i_ref, v_ref, i_hat, h)
    if status == OK:
        _commit_voltage(d, c, v, e, sampled, phase)
    return status, v


@njit(cache=True)
def drive_step(d, c, i_ref, v_ref, omega, i_hat, h):
    """(status, tau, v, i): one step of the drive with inputs held (Drive.step).

    Refused (nothing changed): a non-finite input, a step h the coefficients were not
    prepared for, a non-finite current or torque after the step.
    """
    return _drive_step(d, c, i_ref, v_ref, omega, i_hat, h, False, 0.0, 0.0)


@njit(cache=True)
def drive_step_friction(d, c, i_ref, v_ref, omega, i_hat, h, friction_end, friction_mean):
    """:func:`drive_step` with the friction torque given (its value at the step's end and its
    mean over the step, from :func:`motor.friction.friction_peek`): tau = kt i - friction."""
    return _drive_step(d, c, i_ref, v_ref, omega, i_hat, h, True, friction_end, friction_mean)


@njit(cache=True)
def _drive_step(d, c, i_ref, v_ref, omega, i_hat, h, given, friction_end, friction_mean):
    if not (math.isfinite(omega) and math.isfinite(i_ref) and math.isfinite(v_ref) and math.isfinite(i_hat)):
        return NONFINITE_INPUT, 0.0, 0.0, 0.0
    if h != d[D_H]:
        return UNPREPARED_STEP, 0.0, 0.0, 0.0
    v, e, sampled, phase = _voltage(d, c, i_ref, v_ref, i_hat)
    u = v - d[D_KE] * omega
    i = d[D_A] * d[D_I] + d[D_G] * u                       # (4.162) over the step
    current = i
    friction = friction_end
    if d[D_MEAN_TORQUE] != 0.0:
        current = d[D_WI] * d[D_I] + d[D_WU] * u            # mean current over the step
        friction = friction_mean
    tau = d[D_KT] * current - friction if given else shaft_torque(d, current, omega)
    if not (math.isfinite(i) and math.isfinite(tau)):
        return DIVERGED, tau, v, i
    commit_step(d, c, v, e, sampled, phase, i)
    return OK, tau, v, i


@njit(cache=True)
def observer_estimate(o, v, omega, h):
    """(status, i_hat): the current estimate at the end of a step (CurrentObserver.estimate).

    Refused (nothing changed): a non-finite input, an unprepared h, or a non-finite
    estimate (returned, not kept).
    """
    if not (math.isfinite(v) and math.isfinite(omega)):
        return NONFINITE_INPUT, 0.0
    if h != o[O_H]:
        return UNPREPARED_STEP, 0.0
    omega_held = omega if o[O_STATIC] != 0.0 or o[O_HAS_PREV] == 0.0 else o[O_OMEGA_PREV]
    i_hat = o[O_A] * o[O_I_HAT] + o[O_G] * (v - o[O_KE] * omega_held)
    if not math.isfinite(i_hat):
        return DIVERGED, i_hat
    o[O_I_HAT] = i_hat
    o[O_OMEGA_PREV] = omega
    o[O_HAS_PREV] = 1.0
    return OK, i_hat


# --- the compiled scene's calls (fmus.compiled): inputs x[:n_in], outputs after them ----------

@njit(cache=True)
def drive_io(d, c, x, h):
    """DCMotorDrive: x = [i_ref, v_ref, omega, i_hat | tau, v, i]."""
    status, tau, v, i = drive_step(d, c, x[0], x[1], x[2], x[3], h)
    if status == OK:
        x[4], x[5], x[6] = tau, v, i
    return status


@njit(cache=True)
def drive_io_friction(d, c, x, h, friction_end, friction_mean):
    """DCMotorDrive with its friction given (:func:`drive_step_friction`): x as :func:`drive_io`."""
    status, tau, v, i = drive_step_friction(d, c, x[0], x[1], x[2], x[3], h, friction_end, friction_mean)
    if status == OK:
        x[4], x[5], x[6] = tau, v, i
    return status


@njit(cache=True)
def observer_io(o, x, h):
    """CurrentObserver: x = [v, omega | i_hat]."""
    status, i_hat = observer_estimate(o, x[0], x[1], h)
    if status == OK:
        x[2] = i_hat
    return status
