"""The sampled slaves at a sample time of 2 ms, stepped at h = 1 ms and sampling on sub-step 1
(``sample_phase`` non-zero), against the product's model objects built at T = 2 ms and
stepped once per period here (issue 31, patterns 1 and 2).  The model objects themselves are
held against independent computations at 2 ms in test_oracles_designs.py; these tests catch
a slave that builds or steps its model with the default 1 ms (its ``T`` dropped, a step size
given where the period is meant, ``T`` and ``h`` swapped), or samples on the wrong sub-step.
Each test also checks that the 1 ms model gives other outputs, so it can tell the two apart."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from controller.balance import BalanceController, BalanceSettings, design_balance, get_route
from controller.derivators import Derivator
from controller.fastbalance import INPUTS as BALANCE_INPUTS, OUTPUTS as BALANCE_OUTPUTS
from controller.position import PositionController, default_kt
from controller.strategies import get_strategy
from fmus.cosim.backends import InProcessInstance
from fmus.slave.refusals import ABSURD
from plant import fivebar, get_preset

T, N, PHASE, PERIODS = 2e-3, 2, 1, 40
H = T / N


def _stepped(model, parameters, inputs, outputs):
    """Outputs after each sub-step of the slave; ``inputs(k)`` -> {name: value} of sub-step k.
    Returns (rows, the sampled sub-steps' inputs)."""
    instance = InProcessInstance(model, model.lower())
    instance.initialize({"T": T, "sample_phase": PHASE, **parameters}, 0.0)
    slave, rows, sampled = instance.slave, [], []
    for k in range(PERIODS * N):
        values = inputs(k)
        for name, value in values.items():
            setattr(slave, name, value)
        instance.do_step(k * H, H)
        rows.append([getattr(slave, name) for name in outputs])
        if k % N == PHASE:
            sampled.append((k * H, values))
    return np.array(rows), sampled


def _held(reference_rows, start):
    """The slave's expected rows: ``start`` until the first sample (sub-step PHASE), then each
    period's sample held over the next N sub-steps."""
    rows = [start] * PHASE
    for row in reference_rows:
        rows += [row] * N
    return np.array(rows[:PERIODS * N])


def _angles(k):
    return {"q1": 0.4 + 0.02 * math.sin(0.05 * k) + 1e-4 * (k % N), "q2": 2.1 - 0.03 * math.cos(0.04 * k)}


def test_the_derivator_slave_filters_with_its_T_and_samples_on_its_phase():
    """Bessel filters at fc 60 Hz (velocity) and 25 Hz (acceleration) discretised at 2 ms."""
    outputs = ("dq1", "dq2", "ddq1", "ddq2")
    rows, sampled = _stepped("Derivator", {"fc_vel": 60.0, "fc_acc": 25.0}, _angles, outputs)

    def reference(period):
        d = Derivator(60.0, 25.0, period)
        d.start_at_first_sample(2)
        return [list(d.step_values((v["q1"], v["q2"]), ABSURD)) for _, v in sampled]

    expected = reference(T)
    np.testing.assert_array_equal(rows, _held(expected, [0.0] * 4))
    assert np.max(np.abs(np.array(expected)[:, 0])) > 0.1
    assert not np.allclose(reference(1e-3), expected, rtol=1e-3, atol=0.0)


def test_the_position_controller_slave_runs_its_law_with_its_T():
    """PDMDq with adaptive gains (gamma 4 and 3) and phi = 1, the exact model: the sliding
    integral (6.65) and the adaptive gain (6.66) advance by T a sample."""
    outputs = ("tau1", "tau2", "i_ref1", "i_ref2", "e1", "e2")
    x1, y1 = -0.002, 0.108

    def inputs(k):
        return {**_angles(k), "dq1": 0.1 * math.cos(0.05 * k), "dq2": -0.2, "ddq1": 0.0, "ddq2": 0.3,
                "x_d": x1 + 1e-3 * math.sin(0.03 * k), "y_d": y1, "dx_d": 0.01, "dy_d": 0.0,
                "ddx_d": 0.0, "ddy_d": 0.0}

    # the slave's angles: near the hold point x1 (7.28), world angles
    q1, _, q2, _ = fivebar.inverse_kinematics(get_preset("bench"), x1, y1)

    def near(k):
        values = inputs(k)
        values["q1"], values["q2"] = q1 + 1e-3 * math.sin(0.07 * k), q2 - 1e-3 * math.cos(0.05 * k)
        return values

    gains = {"k1": 50.0, "k2": 40.0, "gamma1": 4.0, "gamma2": 3.0, "phi": 1.0}
    rows, sampled = _stepped("PositionController", {"strategy": "PDMDq", "model": "exact", **gains}, near, outputs)

    def reference(period):
        strategy = get_strategy("PDMDq", "circle").with_(k=(50.0, 40.0), gamma=(4.0, 3.0), phi=1.0)
        c = PositionController(get_preset("bench"), strategy, model="exact", kt=default_kt(), T=period)
        names = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")
        return [list(c.step_with_errors(t, *(v[n] for n in names))) for t, v in sampled]

    expected = reference(T)
    np.testing.assert_array_equal(rows, _held(expected, [0.0] * 6))
    assert not np.allclose(reference(1e-3)[5:], expected[5:], rtol=1e-6, atol=0.0)


def test_the_balance_controller_slave_is_designed_and_samples_at_its_T():
    """The LQR and the observer designed for 2 ms (seed 000's model, python-control's c2d)."""
    outputs = ("v_l", "v_r", "tau_l", "tau_r")

    def inputs(k):
        return {"enc_l": 0.01 + 0.002 * math.sin(0.1 * k), "enc_r": 0.02 - 0.001 * k / PERIODS,
                "gyro": 0.1 * math.cos(0.07 * k)}

    rows, sampled = _stepped("BalanceController", {}, inputs, outputs)

    def reference(period):
        c = BalanceController(design_balance(replace(BalanceSettings(), T=period)), get_route("hold"))
        out = []
        for t, v in sampled:
            c.sample(t, v["enc_l"], v["enc_r"], v["gyro"])
            named = dict(zip(BALANCE_OUTPUTS, c.io[len(BALANCE_INPUTS):].tolist()))
            out.append([named[n] for n in outputs])
        return out

    expected = reference(T)
    np.testing.assert_array_equal(rows, _held(expected, [0.0] * 4))
    assert np.max(np.abs(np.array(expected))) > 0.01
    assert not np.allclose(reference(1e-3), expected, rtol=1e-6, atol=0.0)


@pytest.mark.parametrize("model", ["Derivator", "PositionController", "BalanceController", "CurrentObserver"])
def test_a_step_of_T_itself_at_2ms_samples_every_step(model):
    """h = T = 2 ms is accepted and ``sample_phase`` 1 is refused for it (n = 1), naming the
    phase and [0, 1).  Catches the phase's bound taken from the default T."""
    instance = InProcessInstance(model, "m")
    parameters = {"T": T, "sample_phase": 1}
    if model == "PositionController":
        parameters["model"] = "exact"
    instance.initialize(parameters, 0.0)
    assert instance.slave.do_step(0.0, T) is False
    assert "parameter sample_phase = 1 must be a whole number in [0, T / h) = [0, 1)" in instance.slave.error


def test_the_drive_slave_controls_its_current_at_its_T_with_its_offset():
    """DCMotorDrive at T = 2 ms, h = 0.5 ms, sampling on sub-step 1, with a current-sensor
    offset of 0.03 A (0 by default) and the mean torque: each sub-step's (tau, v, i) is the
    motor.Drive's built with the same T, phase and offset.  Catches the slave's T, phase,
    offset or torque output not passed to its drive."""
    from motor import Drive, get_motor_preset

    n, phase = 4, 1
    h = T / n
    options = {"T": T, "sample_phase": phase, "current_offset": 0.03, "torque_output": "mean"}
    instance = InProcessInstance("DCMotorDrive", "drive")
    instance.initialize({"preset": "motor1", **options}, 0.0)
    slave = instance.slave

    def reference(**changes):
        drive = Drive(get_motor_preset("motor1"), mode="current", method="exact", **{**options, **changes})
        drive.start(0.0, 0.0)
        return drive

    drive, other = reference(), reference(T=1e-3, sample_phase=0)
    rows, expected, at_1ms = [], [], []
    for k in range(60):
        i_ref, omega, i_hat = 1.0 + 0.5 * math.sin(0.2 * k), 3.0 * math.cos(0.05 * k), 0.8 + 0.1 * (k % 3)
        slave.i_ref, slave.omega, slave.i_hat = i_ref, omega, i_hat
        instance.do_step(k * h, h)
        rows.append((slave.tau, slave.v, slave.i))
        expected.append(drive.step(i_ref, 0.0, omega, i_hat, h))
        at_1ms.append(other.step(i_ref, 0.0, omega, i_hat, h))
    np.testing.assert_array_equal(rows, expected)
    volts = np.array(expected)[:, 1]
    for m in range(14):                          # held from sub-step 1 of each period to sub-step 0 of the next
        start = m * n + phase
        assert np.all(volts[start:start + n] == volts[start]) and volts[start] != volts[start - 1], m
    assert not np.allclose(at_1ms, expected, rtol=1e-6, atol=0.0)


def test_the_actuated_plant_slave_gives_each_joint_its_own_drive_at_its_T():
    """ActuatedFiveBarPlant at T = 2 ms, h = 1 ms, sampling on sub-step 1, with unlike drives
    (motor2's preset and R2 = 1.3 ohm on joint 2, current offsets of +0.03 and -0.02 A, 0 by
    default) and an encoder zero error on joint 1: each step's outputs are plant.actuated's
    ActuatedPlant built here from the same simulator and motor.Drive objects.  Catches a
    joint's drive built with the other joint's suffix, the T or phase not passed to them."""
    from motor import Drive, get_motor_preset
    from plant import PlantSimulator
    from plant.actuated import ActuatedPlant

    count = 2.0 * math.pi / 20000
    parameters = {"preset": "bench", "x0": -0.002, "y0": 0.108, "preset1": "motor1", "preset2": "motor2",
                  "R2": 1.3, "current_offset1": 0.03, "current_offset2": -0.02, "encoder_offset1": 2.37 * count}
    instance = InProcessInstance("ActuatedFiveBarPlant", "plant")
    instance.initialize({"T": T, "sample_phase": PHASE, **parameters}, 0.0)
    slave = instance.slave

    def reference(period, phase=PHASE):
        sim = PlantSimulator(get_preset("bench"), x0=-0.002, y0=0.108, encoder_offsets=(2.37 * count, 0.0))
        motor2 = replace(get_motor_preset("motor2"), R=1.3)
        drives = [(1, Drive(get_motor_preset("motor1"), T=period, sample_phase=phase, current_offset=0.03,
                            design_params=get_motor_preset("motor1"))),
                  (2, Drive(motor2, T=period, sample_phase=phase, current_offset=-0.02, design_params=motor2))]
        for _, drive in drives:
            drive.start(0.0, 0.0)
        return ActuatedPlant(sim, drives)

    plant, other = reference(T), reference(1e-3, phase=0)
    names = ("x", "y", "q1_enc", "q2_enc", "i1", "i2", "v1", "v2", "tau1", "tau2")
    got, expected, at_1ms = [], [], []
    for k in range(40):
        i_ref = (1.0 + 0.5 * math.sin(0.2 * k), -0.8 + 0.3 * math.cos(0.1 * k))
        i_hat = (0.9, -0.7 + 0.01 * k)
        slave.i_ref1, slave.i_ref2 = i_ref
        slave.i_hat1, slave.i_hat2 = i_hat
        instance.do_step(k * H, H)
        got.append([getattr(slave, n) for n in names])
        for p, rows in ((plant, expected), (other, at_1ms)):
            p.step(i_ref, i_hat, (0.0, 0.0), H)
            o = p.plant.outputs()
            rows.append([o["x"], o["y"], o["q1_enc"], o["q2_enc"], *p.currents,
                         *(d.v for _, d in p.drives), *p.shaft_torques()])
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-15)
    assert not np.allclose(at_1ms, expected, rtol=1e-6, atol=0.0)


def test_the_dynamic_observer_slave_starts_at_its_i0_and_omega0_and_publishes_on_its_phase():
    """CurrentObserver, kind dynamic, motor2 with ke = 0.06 (its own), i0 = 0.4 A and omega0 =
    3 rad/s (0 by default), T = 2 ms, h = 1 ms, phase 1: the estimate advances every sub-step
    (motor.CurrentObserver from the same start), is published on sub-step 1 of each period and
    held in between; before the first sample the output is i0.  Catches i0 or omega0 not
    reaching the observer, a parameter override lost, the publication on another sub-step."""
    from motor import CurrentObserver, get_motor_preset

    instance = InProcessInstance("CurrentObserver", "obs")
    instance.initialize({"preset": "motor2", "ke": 0.06, "kind": "dynamic", "i0": 0.4, "omega0": 3.0, "T": T,
                         "sample_phase": PHASE}, 0.0)
    slave = instance.slave
    observer = CurrentObserver(replace(get_motor_preset("motor2"), ke=0.06), "dynamic")
    observer.reset(0.4, 3.0)
    assert slave.i_hat == 0.4
    published = 0.4
    for k in range(30):
        v, omega = 2.0 * math.sin(0.3 * k), 3.5 + 0.1 * k      # not omega0 at the first step
        slave.v, slave.omega = v, omega
        instance.do_step(k * H, H)
        estimate = observer.estimate(v, omega, H, k * H)
        if k % N == PHASE:
            published = estimate
        assert slave.i_hat == published, k
    assert published != 0.4
