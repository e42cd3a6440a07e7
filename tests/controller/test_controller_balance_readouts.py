"""What BalanceController gives back after a sample besides its return value: ``u`` (the last
saturated voltages), ``ideal_torques`` ((K_t/R_m) u of its motor preset), ``x_hat`` and
``estimate`` (the observer's prediction for the next sample), each read back against the sample
itself or a quantity computed here."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from controller.balance import BalanceController, BalanceSettings, design_balance, get_route
from motor import get_motor_preset

#: Encoders [rad] and gyro [rad/s] of a tilted, turning start: far enough to saturate a drive.
READINGS = [(0.02, 0.015, -0.3), (0.05, -0.04, 0.6), (0.3, -0.2, 2.5)]


@pytest.mark.parametrize("yaw", [False, True])
def test_the_readouts_after_each_sample_are_that_samples_voltages_torques_and_estimate(yaw):
    """Catches ``u`` reading more or fewer words than the two voltages (or other words), ideal
    torques that are not K_t/R_m times them, and an x_hat that is not the estimate's kept states
    (theta, psi, dtheta, dpsi without yaw: phi and dphi are then 0)."""
    design = design_balance(BalanceSettings(yaw=yaw))
    controller = BalanceController(design, get_route("forward_turn"))
    assert controller.x_hat is None
    motor = get_motor_preset(design.settings.motor_preset)
    for k, readings in enumerate(READINGS):
        v = controller.sample(0.004 * k, *readings)
        assert isinstance(controller.u, np.ndarray) and controller.u.tolist() == list(v)
        assert controller.ideal_torques() == pytest.approx(tuple(motor.kt / motor.R * x for x in v), rel=1e-15)
        estimate = controller.estimate()
        assert list(estimate) == ["theta", "psi", "phi", "dtheta", "dpsi", "dphi"]
        assert all(math.isfinite(x) for x in estimate.values())
        names = list(estimate)
        assert controller.x_hat.tolist() == pytest.approx([estimate[names[s]] for s in design.states], rel=1e-12)
        assert all(estimate[name] == 0.0 for s, name in enumerate(names) if s not in design.states)


def test_the_io_arrays_input_indices_are_where_the_kernel_reads_each_reading():
    """fastbalance.I_ENC_L, I_ENC_R, I_GYRO (the I/O array's published input words) name INPUTS
    in order, and a kernel sample with the readings put there gives
    the voltages BalanceController.sample gives for them.  Catches an index naming another
    input (two readings in one word, one left at zero)."""
    from controller import fastbalance

    assert [fastbalance.INPUTS[i] for i in (fastbalance.I_ENC_L, fastbalance.I_ENC_R, fastbalance.I_GYRO)] == \
        ["enc_l", "enc_r", "gyro"]
    design = design_balance(BalanceSettings(yaw=True))
    controller = BalanceController(design, get_route("forward_turn"))
    buf, x = controller.buf.copy(), np.zeros(fastbalance.IO_SIZE)
    enc_l, enc_r, gyro = READINGS[1]
    x[fastbalance.I_ENC_L], x[fastbalance.I_ENC_R], x[fastbalance.I_GYRO] = enc_l, enc_r, gyro
    assert fastbalance.sample(buf, x, 0.0, math.inf, kernels.Refusal()) == fastbalance.OK
    assert tuple(x[fastbalance.O_V:fastbalance.O_V + 2]) == controller.sample(0.0, enc_l, enc_r, gyro)
