"""What seed 31's C mutants showed no kernel test saw (issue 31, docs/mutation.md): the
actuated 5R's per-motor indexing (two motors with different parameters and currents held
against the unactuated derivative plus B.2 and 4.162 written here), the motor loop's end
(a slot past the outputs keeps its sentinel; under the sanitizer build a read past the
motor rows aborts), and the refusals' code, index and value of the law's table and the
observer's unprepared step."""
from __future__ import annotations

import ctypes
import math
import subprocess
import sys

import numpy as np
import pytest

import kernels
from controller import law
from motor import CurrentObserver, kernel as motor_kernel, motor1
from plant import IntegratorSettings, PlantSimulator, fast5r, get_preset
from tests.support.paths import ROOT

DT = 1e-3
#: Two unlike motors (joint, R, L, kt, ke, b, mu, omega_eps): every column differs.
MOTORS = np.array([[0.0, 1.1, 6.7e-4, 0.056, 0.051, 1.2e-4, 0.04, 0.5],
                   [1.0, 2.3, 1.9e-3, 0.081, 0.077, 3.1e-4, 0.02, 0.2]])
VOLTAGES = np.array([3.0, -5.0])


def _moving_state():
    sim = PlantSimulator(get_preset("bench"), 0.0, 0.15, IntegratorSettings())
    y = sim.y.copy()
    y[7:14] = [0.01, -0.02, 0.0, 0.4, -0.3, -0.5, 0.2]
    return sim._fast, np.concatenate([y, [0.6, -0.9]])


def shaft_torque(m, i, omega):
    """B.2: kt i - b omega - mu tanh(omega / omega_eps)."""
    return m[3] * i - m[5] * omega - m[6] * math.tanh(omega / m[7])


def motor_speeds(z):
    """The speeds of the joints the motors drive: q1's rate, and minus q2's (world -> thesis)."""
    return z[10], -z[12]


def test_each_motor_adds_its_own_torque_and_has_its_own_circuit():
    """dz/dt of the actuated 5R = the plant's derivative with u1 + tau_1 on theta11 and
    u2 - tau_2 on theta21, and L_n di_n/dt = v_n - R_n i_n - ke_n omega_n per motor, each
    with its own current, parameters and speed."""
    kernel, z = _moving_state()
    u1, u2, lam = 0.02, -0.03, 50.0
    got = kernel.actuated_derivative(z, MOTORS, VOLTAGES, u1, u2, lam)
    taus = [shaft_torque(m, z[14 + n], w) for n, (m, w) in enumerate(zip(MOTORS, motor_speeds(z)))]
    plant = kernel.derivative(z[:14], (u1 + taus[0], u2 - taus[1]), lam)
    assert np.allclose(got[:14], plant, rtol=1e-12, atol=1e-12)
    for n, (m, w) in enumerate(zip(MOTORS, motor_speeds(z))):
        assert got[14 + n] == pytest.approx((VOLTAGES[n] - m[1] * z[14 + n] - m[4] * w) / m[2], rel=1e-12)


def test_the_io_step_writes_each_motors_torque_and_nothing_past_them():
    """pc_fivebar_actuated_io: x[first + 11 + n] is motor n's B.2 torque at its new current
    and speed; the slot after the last motor keeps its sentinel."""
    kernel, z = _moving_state()
    state = z.copy()
    first, sentinel = 3, 12345.5
    x = np.full(first + 11 + len(MOTORS) + 1, sentinel)
    x[:2] = 0.0
    context = kernel.context(state, MOTORS, VOLTAGES.copy(), first=first)
    refusal = kernels.Refusal()
    assert fast5r.actuated_io_c(ctypes.addressof(context), kernels.address(x), 0.0, DT, ctypes.byref(refusal)) == 0
    assert x[-1] == sentinel
    speeds = motor_speeds(state)
    for n, m in enumerate(MOTORS):
        assert x[first + 11 + n] == pytest.approx(shaft_torque(m, state[14 + n], speeds[n]), rel=1e-12, abs=1e-15)
    assert state[14] != state[15]


@pytest.mark.tools
def test_the_io_step_reads_no_motor_row_past_the_last_under_the_sanitizer(tmp_path):
    """The step above with the motor rows in a buffer of their own (malloc'd, ASan's
    redzone right behind): the sanitizer build aborts on a read past it."""
    sanitizers = pytest.importorskip("tests.kernels.test_sanitizers")
    if sanitizers.ASAN is None:
        pytest.skip("the C compiler has no AddressSanitizer runtime")
    from kernels import build

    library = build.build(tmp_path / "libparcosim_kernels.so", sanitize=True)
    script = ("import ctypes, numpy as np, kernels; from plant import fast5r; "
              "from tests.kernels.test_oracles_kernels import _moving_state, MOTORS, VOLTAGES; "
              "kernel, z = _moving_state(); motors = np.array(MOTORS); "
              "ctx = kernel.context(z, motors, VOLTAGES.copy(), first=2); x = np.zeros(2 + 11 + 2); "
              "r = kernels.Refusal(); "
              "print(fast5r.actuated_io_c(ctypes.addressof(ctx), kernels.address(x), 0.0, 1e-3, ctypes.byref(r)))")
    run = subprocess.run([sys.executable, "-c", script], cwd=ROOT, env=sanitizers._sanitized_env(library),
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.strip() == "0", run.stderr[-3000:]


@pytest.mark.parametrize("x, y, index, value", [(-0.35, 0.1, 0, -0.35), (0.1, 0.9, 1, 0.9), (0.47, 0.0, 0, 0.47)])
def test_a_point_off_the_table_is_refused_naming_the_coordinate_and_its_value(x, y, index, value):
    """pc_law_interpolate off a 3 x 4 grid: TABLE_OUT, the coordinate (0 x, 1 y), its value exactly."""
    table = np.arange(4 * 5 * law.N_TERMS, dtype=float).reshape(4, 5, law.N_TERMS)
    buf = law.pack_table(-0.2, 0.05, 0.1, table)
    out = np.full(law.N_TERMS, 7.0)
    code, refusal = law.interpolate(buf, x, y, out)
    assert (code, refusal.code, refusal.index, refusal.value) == (law.TABLE_OUT, law.TABLE_OUT, index, value)
    code, _ = law.interpolate(buf, 0.05, 0.2, out)
    assert code == law.OK and out[0] == pytest.approx(table[1:3, 2:4, 0].mean())    # a cell's centre


def test_an_observer_step_of_another_length_is_refused_with_that_length():
    """pc_observer_estimate with h unlike the prepared one: UNPREPARED_STEP, index 0, value h;
    a non-finite omega: NONFINITE_INPUT, index 1, its value; the estimate unchanged."""
    observer = CurrentObserver(motor1)
    observer.prepare_step(1e-3)
    observer.reset(0.25)
    calls = motor_kernel.Calls.observer(observer.buf)
    before = observer.buf.copy()
    assert calls.observer_estimate(2.0, 1.0, 2.5e-3) == motor_kernel.UNPREPARED_STEP
    r = calls.refusal
    assert (r.code, r.index, r.value) == (motor_kernel.UNPREPARED_STEP, 0, 2.5e-3)
    assert calls.observer_estimate(2.0, -math.inf, 1e-3) == motor_kernel.NONFINITE_INPUT
    assert (r.code, r.index, r.value) == (motor_kernel.NONFINITE_INPUT, 1, -math.inf)
    assert np.array_equal(observer.buf, before)


def test_projection_restores_every_joint_rate_of_a_consistent_state():
    """pc_fivebar_project keeps x, y, dx, dy and sets each chain's joint angles and rates from
    them: a state on the loop (the simulator's start with a task velocity) whose joint rates
    are wiped gets all four back, chain 1's included."""
    sim = PlantSimulator(get_preset("bench"), 0.02, 0.15, IntegratorSettings(), dx0=0.4, dy0=-0.3)
    consistent = sim.y.copy()
    assert np.abs(consistent[10:14]).min() > 0.1
    y = consistent.copy()
    y[10:14] = 0.0
    y[3:7] += 1e-4                                   # Newton brings the angles back too
    y = sim._fast.project(y)
    assert np.allclose(y, consistent, rtol=1e-9, atol=1e-10)


@pytest.mark.parametrize("friction", ["tanh", "lugre"])
def test_a_drive_step_or_sample_of_another_length_is_refused_with_that_length(friction):
    """pc_drive_step (through pc_drive_io and pc_drive_step_x) and pc_drive_sample_voltage with h
    unlike the prepared one: UNPREPARED_STEP, index 0, the length h exactly (seed 3901's [191]:
    index and value swapped passed); the drive's buffers and the outputs unchanged.  Drive.step
    prepares a new length on this refusal, so its code, not its index or value, is all it reads."""
    from motor import Drive

    drive = Drive(motor1, friction=friction)
    drive.prepare_step(DT)
    drive.step(0.2, 0.0, 0.5, 0.0, DT)
    buffers = (drive.buf, drive._controller_buf) + (() if drive.lugre is None else (drive.lugre,))
    before = [b.copy() for b in buffers]
    context = motor_kernel.DriveContext(*(None if b is None else kernels.address(b)
                                          for b in (drive.buf, drive._controller_buf, drive.lugre)))
    other = 2.5e-3
    refusal = kernels.Refusal()
    x = np.array([0.2, 0.0, 0.5, 0.0, 7.0, 8.0, 9.0])
    code = motor_kernel.drive_io(ctypes.addressof(context), kernels.address(x), 0.0, other, ctypes.byref(refusal))
    assert (code, refusal.code, refusal.index, refusal.value) == (motor_kernel.UNPREPARED_STEP,) * 2 + (0, other)
    assert list(x[4:]) == [7.0, 8.0, 9.0]
    calls = motor_kernel.Calls.drive(*(drive.buf, drive._controller_buf, drive.lugre))
    assert calls.drive_step(0.2, 0.0, 0.5, 0.0, 4e-3) == motor_kernel.UNPREPARED_STEP
    assert (calls.refusal.code, calls.refusal.index, calls.refusal.value) == (motor_kernel.UNPREPARED_STEP, 0, 4e-3)
    assert calls.sample_voltage(0.2, 0.0, 0.0, 5e-4) == motor_kernel.UNPREPARED_STEP
    assert (calls.refusal.code, calls.refusal.index, calls.refusal.value) == (motor_kernel.UNPREPARED_STEP, 0, 5e-4)
    assert all(np.array_equal(b, a) for b, a in zip(before, buffers))


def test_a_diverged_drive_step_names_the_current_its_value_and_keeps_the_state():
    """Euler with h > 2 L/R multiplies the current by 1 - hR/L < -1 each step until it is not
    finite: pc_drive_step refuses that step with DIVERGED, index 0 (the current, not the
    torque) and the current's value, which x carries too (the message's), the buffers kept."""
    from motor import Drive

    drive = Drive(motor1.with_(L=motor1.R * DT / 100), mode="voltage", method="euler")
    drive.prepare_step(DT)
    calls = motor_kernel.Calls.drive(drive.buf, drive._controller_buf, None)
    for _ in range(1000):
        before = drive.buf.copy()
        code = calls.drive_step(0.0, 1.0, 0.0, 0.0, DT)
        if code != motor_kernel.OK:
            break
    r = calls.refusal
    assert (code, r.code, r.index) == (motor_kernel.DIVERGED, motor_kernel.DIVERGED, 0)
    assert not math.isfinite(r.value) and np.array_equal([calls.x[7]], [r.value], equal_nan=True)
    assert math.isfinite(before[motor_kernel.index(motor_kernel.DRIVE, "i")])
    assert np.array_equal(drive.buf, before)
