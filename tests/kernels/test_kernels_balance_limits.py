"""The balance controller's C sample (kernels/src/balance.c) at the lower ends of its sizes:
a design that keeps no state and reads no measurement (n = 0, ny = 0) is a valid buffer (the
sizes are integers in [0, N_MAX] and [0, NY_MAX], balance.h) whose command is 0 V."""
from __future__ import annotations

import math

import numpy as np

import kernels
from controller import fastbalance
from tests.kernels.test_kernels_wheeled import _buffer


def test_a_design_of_no_state_and_no_measurement_is_accepted_and_commands_nothing():
    """Catches ``>`` for ``>=`` at the lower end of the size checks: n = 0 and ny = 0 are sizes
    in range; with no state the LQR sum is empty, so both voltages and torques are 0 and the
    sample still reports the route's reference (x_d > 0 once the drive window has started)."""
    buf, x, refusal = _buffer(yaw=False), np.zeros(fastbalance.IO_SIZE), kernels.Refusal()
    buf[fastbalance.BUFFER["n"].start] = 0.0
    buf[fastbalance.BUFFER["ny"].start] = 0.0
    x[:3] = 0.01, 0.02, 0.3
    assert fastbalance.sample(buf, x, 1.0, math.inf, refusal) == fastbalance.OK
    out = dict(zip(fastbalance.OUTPUTS, x[3:]))
    assert [out["v_l"], out["v_r"], out["tau_l"], out["tau_r"]] == [0.0, 0.0, 0.0, 0.0]
    assert out["x_d"] > 0.0


def test_one_past_either_size_is_refused_by_its_word():
    """n = N_MAX + 1 = 7 and ny = NY_MAX + 1 = 4 are refused naming n and ny; n = -1 likewise."""
    for word, value in (("n", 7.0), ("ny", 4.0), ("n", -1.0), ("ny", -1.0)):
        buf, x, refusal = _buffer(), np.zeros(fastbalance.IO_SIZE), kernels.Refusal()
        buf[fastbalance.BUFFER[word].start] = value
        assert fastbalance.sample(buf, x, 0.0, math.inf, refusal) == fastbalance.BAD_BUFFER
        assert (refusal.index, refusal.value) == (fastbalance.BUFFER[word].start, value), word
