"""TRANSITIONAL numba copies of the drive's, the observer's and LuGre's steps, for the compiled
scene loop only (the code fmus/adapters.py generates for fmus/compiled.py calls them inside numba).

The one implementation is C (kernels/src/drive.c, observer.c): :class:`motor.Drive`,
:class:`motor.CurrentObserver`, :class:`motor.CurrentController` and :mod:`motor.friction` call
it through ctypes.  This file goes when the compiled loop runs the C kernels' ``pc_*_io``
functions (issue 27); until then tests/test_kernels_drive.py holds the compiled loop's results
to the C kernel's.  The buffers are the C structs' (offsets read from kernels.layout); the
LuGre functions are registered as numba implementations of :mod:`motor.friction`'s, the names
the generated loop calls.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.extending import overload

from motor import friction, kernel

# --- status codes (drive.h) ----------------------------------------------------------------
OK, NONFINITE_INPUT, UNPREPARED_STEP, DIVERGED = kernel.OK, kernel.NONFINITE_INPUT, kernel.UNPREPARED_STEP, kernel.DIVERGED

_C, _D, _O, _F = kernel.CONTROLLER, kernel.DRIVE, kernel.OBSERVER, kernel.LUGRE
C_ALPHA, C_BETA, C_GAMMA, C_DELTA, C_VMAX = (kernel.index(_C, n) for n in ("alpha", "beta", "gamma", "delta", "v_max"))
C_U1, C_U2, C_E1, C_E2 = (kernel.index(_C, n) for n in ("u1", "u2", "e1", "e2"))
CONTROLLER_SIZE = kernel.size(_C)
(D_CURRENT_MODE, D_MEAN_TORQUE, D_KE, D_KT, D_B, D_MU, D_OMEGA_EPS, D_VMAX, D_T, D_H, D_A, D_G, D_WI, D_WU,
 D_PHASE_STEP, D_I, D_V, D_PHASE, D_PWM_QUANTUM, D_I_OFFSET, D_I_NOISE, D_NOISE_SEED, D_NOISE_INSTANCE,
 D_SAMPLE) = (kernel.index(_D, n) for n in (
    "current_mode", "mean_torque", "ke", "kt", "b", "mu", "omega_eps", "v_max", "T", "h", "a", "g", "w_i", "w_u",
    "phase_step", "i", "v", "phase", "pwm_quantum", "i_offset", "i_noise", "noise_seed", "noise_instance", "sample"))
DRIVE_SIZE = kernel.size(_D)
PHASE_TOL = 1e-6
O_STATIC, O_KE, O_H, O_A, O_G, O_I_HAT, O_OMEGA_PREV, O_HAS_PREV = (kernel.index(_O, n) for n in (
    "is_static", "ke", "h", "a", "g", "i_hat", "omega_prev", "has_prev"))
OBSERVER_SIZE = kernel.size(_O)
F_FC, F_FS, F_OMEGA_S, F_SIGMA0, F_SIGMA1, F_SIGMA2, F_Z = (kernel.index(_F, n) for n in (
    "Fc", "Fs", "omega_s", "sigma0", "sigma1", "sigma2", "z"))


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


# --- LuGre (motor.friction's functions inside the compiled loop) ----------------------------

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
    if x < 1e-3:
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



# Inside numba, motor.friction's functions are these (their py_func: same signatures).
overload(friction.stribeck)(lambda f, omega: stribeck.py_func)
overload(friction.bristle_rate)(lambda f, z, omega: bristle_rate.py_func)
overload(friction.friction_force)(lambda f, z, omega: friction_force.py_func)
overload(friction.steady_deflection)(lambda f, omega: steady_deflection.py_func)
overload(friction.advance)(lambda f, z0, omega, h: advance.py_func)
overload(friction.friction_peek)(lambda f, omega, h: friction_peek.py_func)
overload(friction.friction_commit)(lambda f, z: friction_commit.py_func)
