"""The DC drive against an oracle written here from the thesis' equations alone (issue 31,
pattern 1 and 2): a second controller period (T = 2 ms, four steps per period, so the
controller samples one step in four and holds its voltage between), a non-zero current
offset, LuGre friction (the torque kt i - F at the step's end or its mean), the design of
K(z) held against scipy's own ZOH discretisation, and the exported C helpers no drive step
calls (pc_drive_armature_rate, pc_lugre_push)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import cont2discrete

from motor import Drive, friction as fr, kernel, motor1, motor2

T = 2e-3
STEPS_PER_PERIOD = 4
H = T / STEPS_PER_PERIOD
OFFSET = 0.03


def stribeck(m, omega):
    """G(omega) of the LuGre paper's (3)."""
    return m.Fc + (m.Fs - m.Fc) * math.exp(-(omega / m.omega_s) ** 2)


def bristles(m, z0, omega, h):
    """(z(h), F at h, mean F over h) of LuGre (1), (4) with omega held, from z0: the linear
    ODE dz/dt = omega - r z, r = sigma0 |omega| / G, solved in closed form."""
    g = stribeck(m, omega)
    r = m.sigma0 * abs(omega) / g
    if r == 0.0:
        z, mean_z = z0 + omega * h, z0 + 0.5 * omega * h
    else:
        z = z0 * math.exp(-r * h) + omega / r * (1.0 - math.exp(-r * h))
        mean_z = omega / r + (z0 - omega / r) * (1.0 - math.exp(-r * h)) / (r * h)
    force = m.sigma0 * z + m.sigma1 * (omega - r * z) + m.sigma2 * omega
    mean_force = m.sigma0 * mean_z + m.sigma1 * (z - z0) / h + m.sigma2 * omega
    return z, force, mean_force


class OracleDrive:
    """The current-mode drive of appendix C and (4.162), in plain Python: K(z) as its
    difference equation sampled every T, its saturated output held, the current exact over
    each step, LuGre friction."""

    def __init__(self, params, design, offset):
        self.p, self.d, self.offset = params, design, offset
        self.lugre = fr.LuGre.of_motor(params)
        self.i = self.z = 0.0
        self.u = [0.0, 0.0]
        self.e = [0.0, 0.0]
        self.v = 0.0
        self.k = 0

    def step(self, i_ref, omega, i_hat, h, mean):
        p, d = self.p, self.d
        if self.k % STEPS_PER_PERIOD == 0:
            e = i_ref - (i_hat + self.offset)
            raw = (1 + d.delta) * self.u[0] - d.delta * self.u[1] + d.alpha * e + d.beta * self.e[0] + d.gamma * self.e[1]
            self.v = min(max(raw, -p.v_max), p.v_max)
            self.u = [self.v, self.u[0]]
            self.e = [e, self.e[0]]
        self.k += 1
        u = self.v - p.ke * omega
        a = math.exp(-p.R * h / p.L)
        i_end = a * self.i + (1 - a) * u / p.R
        i_mean = u / p.R + (self.i - u / p.R) * (1 - a) / (p.R * h / p.L)
        z, f_end, f_mean = bristles(self.lugre, self.z, omega, h)
        tau = p.kt * i_mean - f_mean if mean else p.kt * i_end - f_end
        self.i, self.z = i_end, z
        return tau, self.v, i_end


@pytest.mark.parametrize("torque_output", ["end", "mean"])
@pytest.mark.parametrize("params", [motor1, motor2], ids=["motor1", "motor2"])
def test_drive_at_a_2ms_period_with_an_offset_and_lugre_is_the_oracle(params, torque_output):
    """Forty steps of h = T/4 with i_ref, omega and i_hat changing every step and v_ref
    (unused in current mode) different from omega: the outputs agree step by step, so the
    controller samples at phase 0 only, commits only then, reads i_hat + offset, and the
    torque is kt i - F of the right friction (end or mean) at the right speed."""
    drive = Drive(params, T=T, friction="lugre", current_offset=OFFSET, torque_output=torque_output)
    oracle = OracleDrive(params, drive.controller.design, OFFSET)
    for k in range(40):
        i_ref, omega, i_hat = 0.4 * math.sin(0.3 * k), 0.5 + 2.0 * math.cos(0.2 * k), 0.02 * k
        got = drive.step(i_ref, -7.0, omega, i_hat, H)
        want = oracle.step(i_ref, omega, i_hat, H, torque_output == "mean")
        assert got == pytest.approx(want, rel=1e-9, abs=1e-12), k
    assert drive.z == pytest.approx(oracle.z, rel=1e-9)


def test_the_voltage_changes_only_at_the_start_of_a_period():
    """h = T/4: the applied voltage of steps 1-3 of each period is step 0's (held)."""
    drive = Drive(motor1, T=T)
    voltages = [drive.step(0.5 * (-1) ** k, 0.0, 1.0, 0.1 * k, H)[1] for k in range(12)]
    for start in range(0, 12, STEPS_PER_PERIOD):
        assert voltages[start:start + STEPS_PER_PERIOD] == [voltages[start]] * STEPS_PER_PERIOD
    assert len(set(voltages[::STEPS_PER_PERIOD])) == 3


def test_the_torque_with_lugre_is_kt_i_minus_the_bristle_force():
    """Drive.torque(omega) at a deflection z and a speed unlike z: kt i - F(z, omega) (4)."""
    drive = Drive(motor1, friction="lugre")
    drive.i, drive.z = 0.7, 3e-4
    m = fr.LuGre.of_motor(motor1)
    omega = 0.05
    r = m.sigma0 * abs(omega) / stribeck(m, omega)
    force = m.sigma0 * drive.z + m.sigma1 * (omega - r * drive.z) + m.sigma2 * omega
    assert drive.torque(omega) == pytest.approx(motor1.kt * 0.7 - force, rel=1e-12)


@pytest.mark.parametrize("params", [motor1, motor2], ids=["motor1", "motor2"])
@pytest.mark.parametrize("period", [1e-3, 2e-3, 5e-4])
def test_current_controller_design_places_the_poles_on_scipys_zoh_model(params, period):
    """The design at T: the characteristic polynomial (z - 1)(z - delta) D(z) + (alpha z^2 +
    beta z + gamma) N(z), with N/D the ZOH model scipy computes from the state space of
    (B.10) (not python-control's c2d the design uses), has roots 0, 0.6, 0.7 and the plant
    zero; the design's T is the one asked for."""
    p = params
    A = np.array([[-p.R / p.L, -p.ke / p.L], [p.kt / p.J_rotor, -p.b / p.J_rotor]])
    B = np.array([[1.0 / p.L], [0.0]])
    Ad, Bd, _, _, _ = cont2discrete((A, B, np.array([[1.0, 0.0]]), np.zeros((1, 1))), period, method="zoh")
    den = np.poly(Ad)
    num = np.poly(Ad - Bd @ np.array([[1.0, 0.0]])) - den      # C adj(zI - A) B = det(zI - A + BC) - det(zI - A)
    num = np.trim_zeros(num, "f")
    design = Drive(params, T=period).controller.design
    assert design.T == period
    char = np.polyadd(np.polymul(np.polymul([1.0, -1.0], [1.0, -design.delta]), den),
                      np.polymul([design.alpha, design.beta, design.gamma], num))
    zero = -num[1] / num[0]
    assert np.allclose(char / char[0], np.poly([0.0, 0.6, 0.7, zero]), atol=1e-9)
    assert design.delta == pytest.approx(zero, rel=1e-9)


def test_armature_rate_is_4_162_with_every_argument_in_its_place():
    """pc_drive_armature_rate(R, L, ke, v, i, omega) = (v - R i - ke omega) / L, values all unlike."""
    R, L, ke, v, i, omega = 1.3, 7e-4, 0.06, 11.0, 0.8, 25.0
    assert kernel.armature_rate(R, L, ke, v, i, omega) == pytest.approx((v - R * i - ke * omega) / L, rel=1e-14)


@pytest.mark.parametrize("kind, a, b", [(0, 0.2, 0.0), (1, 0.08, 40.0), (2, 3.0, 0.05)])
def test_lugre_push_is_the_mass_on_bristles_of_the_paper(kind, a, b):
    """pc_lugre_push against the same scheme written here: the speed held over each step,
    the bristles exact (closed form above), the mass integrated with the mean friction;
    force a t, a sin(b t) or a spring a (b t - x) evaluated mid-step."""
    model = fr.LuGre(Fc=0.05, Fs=0.08, omega_s=0.02, sigma0=50.0, sigma1=0.3, sigma2=0.01)
    f = fr.new_lugre(model)
    mass, h, n = 0.02, 1e-3, 200
    rows = np.zeros(3 * n)
    kernel.lugre_push(f.ctypes.data, kind, a, b, mass, h, n, rows.ctypes.data)
    x = v = z = 0.0
    want = []
    for k in range(n):
        t = (k + 0.5) * h
        force = (a * t, a * math.sin(b * t), a * (b * t - (x + 0.5 * h * v)))[kind]
        z_end, _, mean_force = bristles(model, z, v, h)
        acc = (force - mean_force) / mass
        x, v, z = x + h * v + 0.5 * h * h * acc, v + h * acc, z_end
        want += [x, v, z]
    assert np.allclose(rows, want, rtol=1e-9, atol=1e-13)
    assert np.ptp(rows[1::3]) > 0.0     # it moved: the friction was crossed
