"""Discrete balance controller of the wheeled pendulum (seed 000): observer + LQR at T = 1 ms.

Design (:func:`design_balance`), with python-control, on OUR model:

1. the pendulum linearised at the upright at rest (:func:`plant.wheeled.upright_linearisation`,
   state x = (theta, psi, phi, theta', psi', phi'), wheel torques in);
2. the drives of seed 000 (22) in front of it: tau_j = (K_t/R_m) v_j - c omega_j, omega_j the
   motor speed relative to the body, c = K_t K_e/R_m (back-EMF, quasi-static electrics; 0 with
   ideal electrics) + f_m (friction; 0 without);
3. ``control.c2d`` (zero-order hold, the voltages are held over a sample), then
   ``control.dlqr`` with Bryson weights :data:`STATE_SCALE`, :data:`VOLTAGE_SCALE` on pitch,
   wheel position and yaw (the yaw rows dropped when the yaw is locked);
4. a steady-state Kalman predictor-corrector (``control.dlqe``) on what a real robot
   measures: the wheel encoders (theta_l,r - psi, quantised) and a pitch-rate gyro (psi').
   psi itself is never measured: integrating the gyro alone would leave the initial tilt
   unknown (released at 5 degrees, it would balance around the wrong attitude), but gravity
   puts psi into psi'' (the gyro's derivative), so (A, C) is observable and the observer
   recovers psi, the initial tilt included, from the gyro and the encoders through the model.

At each sample k (t = k T): correct the estimate with the measurements, u = -K (x_hat - x_ref(t)),
saturate at +-v_battery, predict the next estimate with the voltage actually applied.
The reference (:class:`Route`) starts at the origin, heading +x, theta = 0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import control   # at import (an FMU's instantiation), not in the design: importing it takes 1-7 s
import numpy as np

import kernels
from controller import fastbalance
from controller.trajectories import SMOOTHSTEP_COEFFICIENTS, SMOOTHSTEP_SLOPE_COEFFICIENTS

#: Bryson's rule: the largest acceptable excursion of each state, (theta [rad], psi [rad],
#: phi [rad], theta' [rad/s], psi' [rad/s], phi' [rad/s]); Q = diag(1/scale^2).
STATE_SCALE = (0.5, 0.02, 0.05, 5.0, 0.5, 1.0)
#: Acceptable voltage [V]: R = 1/VOLTAGE_SCALE^2 per motor.
VOLTAGE_SCALE = 3.0
#: Standard deviations assumed by the observer design: voltage disturbance [V] and body
#: torque disturbance [N m] (process), gyro noise [rad/s] (measurement); the encoder's is
#: its quantisation, count/sqrt(12).  The body torque's is small on purpose: the observer
#: tells a tilt from a torque only through the model's gravity term, and with 1e-2 N m it took
#: the 5 degree release tilt for a torque (estimate still 0.5 degrees off after 5 s, 16 mm
#: final position error); with 1e-4 it is within 0.06 degrees after 1 s (docs/pendulum.md).
VOLTAGE_NOISE = 0.1
BODY_TORQUE_NOISE = 1e-4
GYRO_NOISE = 1e-3
ELECTRICS = ("quasi_static", "ideal")
#: Shortest sample time designed for [s]: below it the Riccati solvers take seconds (12 s at
#: 1 us, measured) for a rate no robot's controller runs at; the balance is lost above 6 ms.
MIN_SAMPLE_TIME = 1e-5
ROUTES = ("hold", "forward_turn")


@dataclass(frozen=True)
class BalanceSettings:
    """What the balance controller is designed for.

    Parameters
    ----------
    T : float
        Sample time [s].
    v_battery : float
        Voltage saturation [V] (seed 000 gives none: 8 V is our assumption).
    electrics : {"quasi_static", "ideal"}
        The drives' model: seed 000's (22) with L = 0, or ideal torque sources
        tau = (K_t/R_m) v without back-EMF.
    friction : bool
        The motors' f_m is modelled.
    yaw : bool
        Control the yaw (False: the heading is locked, pitch and wheel position only).
    encoder_counts : int
        Encoder counts per revolution (sets the observer's measurement noise).
    motor_preset : str
        :mod:`motor.presets` name of the drives' motor.
    """

    T: float = 1e-3
    v_battery: float = 8.0
    electrics: str = "quasi_static"
    friction: bool = True
    yaw: bool = True
    encoder_counts: int = 4096
    motor_preset: str = "seed000"

    def validate(self) -> "BalanceSettings":
        if not (math.isfinite(self.T) and MIN_SAMPLE_TIME <= self.T <= 1.0):
            raise ValueError(f"parameter T = {self.T!r} s must be in [{MIN_SAMPLE_TIME:g}, 1] s")
        if not (math.isfinite(self.v_battery) and self.v_battery > 0.0):
            raise ValueError(f"parameter v_battery = {self.v_battery!r} V must be > 0")
        if self.electrics not in ELECTRICS:
            raise ValueError(f"parameter electrics = {self.electrics!r}; valid: {', '.join(ELECTRICS)}")
        if not (isinstance(self.encoder_counts, int) and self.encoder_counts > 0):
            raise ValueError(f"parameter encoder_counts = {self.encoder_counts!r} must be a positive integer")
        return self


@dataclass(frozen=True)
class BalanceDesign:
    """The discrete design: state indices kept, Ad, Bd, gain K, observer gain Lo, C, poles."""

    states: tuple
    Ad: np.ndarray
    Bd: np.ndarray
    K: np.ndarray
    C: np.ndarray
    Lo: np.ndarray
    closed_loop_poles: np.ndarray
    observer_poles: np.ndarray
    settings: BalanceSettings = field(default_factory=BalanceSettings)


def voltage_model(settings: BalanceSettings, params=None):
    """(A, B) of the pendulum with its drives, voltages (v_l, v_r) in, full 6-state."""
    from motor import get_motor_preset
    from plant.wheeled import SEED, upright_linearisation

    p = SEED if params is None else params
    motor = get_motor_preset(settings.motor_preset)
    A, B = upright_linearisation(p)
    c = (motor.kt * motor.ke / motor.R if settings.electrics == "quasi_static" else 0.0)
    c += motor.b if settings.friction else 0.0
    half = p.W / (2.0 * p.R)
    speeds = np.array([[0, 0, 0, 1.0, -1.0, -half], [0, 0, 0, 1.0, -1.0, half]])   # omega_l, omega_r
    return A - c * B @ speeds, motor.kt / motor.R * B


def design_balance(settings: BalanceSettings = BalanceSettings(), params=None) -> BalanceDesign:
    """The LQR gain and the observer of the module docstring.

    Raises
    ------
    ValueError
        A bad setting (named), or a design python-control cannot solve (naming T).
    """
    s = settings.validate()
    try:
        return _design(s, params)
    except (ValueError, TypeError, ArithmeticError, np.linalg.LinAlgError) as exc:   # ControlArgument: TypeError
        raise ValueError(f"the balance design failed for T = {s.T!r} s, electrics = {s.electrics!r}, "
                         f"friction = {s.friction!r}, yaw = {s.yaw!r}, encoder_counts = {s.encoder_counts!r}: "
                         f"{exc}") from None


def _design(s: BalanceSettings, params) -> BalanceDesign:
    A, B = voltage_model(s, params)
    states = (0, 1, 2, 3, 4, 5) if s.yaw else (0, 1, 3, 4)
    A, B = A[np.ix_(states, states)], B[states, :]
    n = len(states)
    sys_d = control.c2d(control.ss(A, B, np.eye(n), np.zeros((n, 2))), s.T, method="zoh")
    Ad, Bd = np.asarray(sys_d.A), np.asarray(sys_d.B)
    Q = np.diag([1.0 / STATE_SCALE[i] ** 2 for i in states])
    K, _, poles = control.dlqr(Ad, Bd, Q, np.eye(2) / VOLTAGE_SCALE ** 2)
    # Measurements: mean encoder theta - psi, gyro psi', yaw (R/W)(enc_r - enc_l).
    from plant.wheeled import SEED

    p = SEED if params is None else params
    count = 2.0 * math.pi / s.encoder_counts
    rows = [[1.0, -1.0, 0, 0, 0, 0], [0, 0, 0, 0, 1.0, 0]]
    noise = [count ** 2 / 24.0, GYRO_NOISE ** 2]     # the mean of two encoders: var/2
    if s.yaw:
        rows.append([0, 0, 1.0, 0, 0, 0])
        noise.append((p.R / p.W) ** 2 * count ** 2 / 6.0)
    C = np.array(rows)[:, states]
    # Process noise: the voltages through Bd, a body torque through its column of B (times T).
    G = np.column_stack([Bd, s.T * _body_torque_column(params)[list(states)]])
    QN = np.diag([VOLTAGE_NOISE ** 2, VOLTAGE_NOISE ** 2, BODY_TORQUE_NOISE ** 2])
    # dlqe gives the predictor gain Ad M and the a-priori covariance P; the sample corrects first
    # (x += Lo (y - C x)) and then predicts, so it needs the filter gain M = P C' (C P C' + V)^-1.
    V = np.diag(noise)
    _, P, _ = control.dlqe(Ad, G, C, QN, V)
    Lo = P @ C.T @ np.linalg.inv(C @ P @ C.T + V)
    observer_poles = np.linalg.eigvals(Ad - Ad @ Lo @ C)
    return BalanceDesign(states, Ad, Bd, np.asarray(K), C, np.asarray(Lo), np.asarray(poles), observer_poles, s)


def _body_torque_column(params):
    """d x'/d tau_d at the upright: how a torque on the body drives the 6 states' derivatives."""
    from plant.wheeled import SEED, upright_mass_matrix

    pitch, _ = upright_mass_matrix(SEED if params is None else params)
    b = np.zeros(6)
    b[3:5] = np.linalg.solve(pitch, [0.0, 1.0])
    return b


@dataclass(frozen=True)
class Route:
    """Reference: ``distance`` [m] forward along +x over ``drive`` (start, end) [s], then a
    left turn in place by ``turn`` [rad] over ``turning`` (start, end) [s], each with the
    smooth step s(tau) of (7.27); "hold" is distance = turn = 0."""

    distance: float = 0.0
    turn: float = 0.0
    drive: tuple = (0.5, 5.5)
    turning: tuple = (6.0, 8.0)


def get_route(name: str) -> Route:
    """``"hold"`` (stay at the origin) or ``"forward_turn"`` (1 m forward, then 90 degrees left)."""
    if name == "hold":
        return Route()
    if name == "forward_turn":
        return Route(distance=1.0, turn=0.5 * math.pi)
    raise ValueError(f"route = {name!r}; valid: {', '.join(ROUTES)}")


#: The C sample's refusal codes -> their record and message.
REASONS = {
    fastbalance.BAD_INPUT: kernels.Reason("input_not_finite", fastbalance.INPUTS, "",
                                          "input {variable} = {value!r} at t = {time:.6g} s is not finite"),
    fastbalance.INPUT_LIMIT: kernels.Reason("input_absurd", fastbalance.INPUTS, "",
                                            "input {variable} = {value!r} at t = {time:.6g} s is absurd: "
                                            "|{variable}| must be <= {limit:g}"),
    fastbalance.BAD_BUFFER: kernels.Reason("bad_buffer", fastbalance.WORD_NAMES, "",
                                           "the balance controller's buffer word {variable} = {value!r} at "
                                           "t = {time:.6g} s is not a size or state index its arrays have"),
}


def _bind_sample(buf, io):
    """(sample(t, limit), its refusal record): ``pc_balance_sample`` on a controller's ``buf``
    and ``io``, kept outside the controller (:func:`kernels.owned`)."""
    refusal = kernels.Refusal()
    return kernels.bind(fastbalance.c_sample, buf, io, kernels.PER_CALL, kernels.PER_CALL, refusal), refusal


class BalanceController:
    """The sampled controller: observer, LQR, saturation (see the module docstring).

    Each sample is the C ``pc_balance_sample`` on :attr:`buf` (:mod:`controller.fastbalance`:
    the arithmetic the FMU and the compiled loop run too); :attr:`io` holds the last sample's
    inputs and outputs.

    Parameters
    ----------
    design : BalanceDesign
    route : Route
    R, W : float
        Wheel radius and track width the encoders are converted with [m].
    """

    #: Kernel buffers -> the function giving the words a run changes; a restored FMU state may
    #: not change the others (:mod:`fmus.slave.state`).
    KERNEL_BUFFERS = {"buf": fastbalance.run_state_words}

    def __init__(self, design: BalanceDesign, route: Route = Route(), R: float = 0.04, W: float = 0.14):
        from motor import get_motor_preset

        self.design, self.route, self.R, self.W = design, route, R, W
        motor = get_motor_preset(design.settings.motor_preset)
        self.torque_per_volt = motor.kt / motor.R
        self.buf = fastbalance.pack(design, route, R, W, self.torque_per_volt, SMOOTHSTEP_COEFFICIENTS,
                                    SMOOTHSTEP_SLOPE_COEFFICIENTS)
        self.io = np.zeros(fastbalance.IO_SIZE)

    @property
    def x_hat(self):
        """The observer's estimate for the next sample (kept states), None before the first sample."""
        if self.buf[fastbalance.B_STARTED] == 0.0:
            return None
        return self.buf[fastbalance.B_X_HAT:fastbalance.B_X_HAT + len(self.design.states)].copy()

    @property
    def u(self) -> np.ndarray:
        """The last saturated voltages (v_l, v_r) [V]."""
        return self.buf[fastbalance.B_U:fastbalance.B_U + 2].copy()

    def sample(self, t: float, enc_l: float, enc_r: float, gyro: float):
        """Read the sensors at time t; return the saturated voltages (v_l, v_r) held over the sample.

        Raises
        ------
        kernels.Refused
            An input that is not finite (named, with the time), or a buffer word out of range.
        """
        sample, refusal = kernels.owned(self, (self.buf, self.io), _bind_sample)
        io = self.io
        io[0], io[1], io[2] = enc_l, enc_r, gyro
        code = sample(t, math.inf)
        if code != fastbalance.OK:
            raise kernels.refused(REASONS, refusal, t, limit=math.inf)
        return float(io[fastbalance.O_V]), float(io[fastbalance.O_V + 1])

    def ideal_torques(self) -> tuple:
        """(K_t/R_m) (v_l, v_r): the wheel torques of ideal drives for the last voltages [N m]."""
        return float(self.io[fastbalance.O_TAU]), float(self.io[fastbalance.O_TAU + 1])

    def estimate(self) -> dict:
        """The observer's prediction for the next sample: theta, psi, phi and rates."""
        names = ("theta", "psi", "phi", "dtheta", "dpsi", "dphi")
        return {name: float(self.io[fastbalance.O_HAT + i]) for i, name in enumerate(names)}
