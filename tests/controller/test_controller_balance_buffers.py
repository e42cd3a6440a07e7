"""The balance kernel's Python binding (controller/fastbalance.py ``sample``): each of its two
buffers is checked (a float64 ndarray of at least its C size) before the kernel reads it, a
longer one is read only up to its size, and a refused call writes nothing."""
from __future__ import annotations

import numpy as np
import pytest

import kernels
from controller import fastbalance
from controller.balance import BalanceController, BalanceSettings, design_balance, get_route

T = 0.25


@pytest.fixture(scope="module")
def controller():
    return BalanceController(design_balance(BalanceSettings(yaw=False)), get_route("forward_turn"))


def _buffers(controller):
    x = np.zeros(fastbalance.IO_SIZE)
    x[:3] = (0.02, 0.015, -0.3)                      # encoders and gyro: a tilted, turning start
    return [controller.buf.copy(), x]


@pytest.mark.parametrize("k, size", [(0, fastbalance.BUF_SIZE), (1, fastbalance.IO_SIZE)])
def test_each_buffer_is_checked_before_the_kernel_reads_it(controller, k, size):
    """Catches a binding that leaves the I/O array (or the buffer) out of its check, or checks
    it against the other's size: a short, float32, int64 or list buffer is refused word for
    word and the other buffer is left as it was."""
    buffers = _buffers(controller)
    assert fastbalance.sample(*buffers, T, 1e6, kernels.Refusal()) == fastbalance.OK     # whole: accepted
    for bad in (np.zeros(size - 1), np.zeros(size, dtype=np.float32), np.zeros(size, dtype=np.int64),
                [0.0] * size):
        buffers = _buffers(controller)
        other = buffers[1 - k].copy()
        buffers[k] = bad
        with pytest.raises(ValueError) as caught:
            fastbalance.sample(*buffers, T, 1e6, kernels.Refusal())
        assert str(caught.value) == f"a balance kernel buffer must be a float64 array of >= {size} words"
        assert np.array_equal(buffers[1 - k], other)


def test_longer_buffers_are_read_only_up_to_their_sizes(controller):
    """Catches a check that wants the exact size (``==`` for ``>=``): spare words after either
    buffer change nothing the kernel writes and are left alone."""
    buf, x = _buffers(controller)
    code = fastbalance.sample(buf, x, T, 1e6, kernels.Refusal())
    long_buf, long_x = _buffers(controller)
    long_buf, long_x = np.concatenate([long_buf, [np.nan, 1e300]]), np.concatenate([long_x, [np.nan, -1e300]])
    assert fastbalance.sample(long_buf, long_x, T, 1e6, kernels.Refusal()) == code == fastbalance.OK
    assert np.array_equal(long_x[:fastbalance.IO_SIZE], x) and np.array_equal(long_buf[:fastbalance.BUF_SIZE], buf)
    assert np.isnan(long_x[-2]) and long_x[-1] == -1e300 and np.isnan(long_buf[-2]) and long_buf[-1] == 1e300


def test_only_the_inputs_are_checked_and_read_the_output_slots_are_written_whatever_they_held(controller):
    """The I/O array holds the inputs, then the outputs: what the output slots hold before a
    sample (NaN, beyond the input limit: an FMU's starts, the last sample's values) is neither
    checked nor read, and each is overwritten with what the sample of zeroed slots writes.
    Catches an input check that runs one word past the inputs."""
    buf, x = _buffers(controller)
    assert fastbalance.sample(buf, x, T, 1.0, kernels.Refusal()) == fastbalance.OK
    for held in (np.nan, 2.0, -np.inf):
        other_buf, other_x = _buffers(controller)
        other_x[len(fastbalance.INPUTS):] = held
        assert fastbalance.sample(other_buf, other_x, T, 1.0, kernels.Refusal()) == fastbalance.OK, held
        assert np.array_equal(other_x, x, equal_nan=True) and np.array_equal(other_buf, buf, equal_nan=True)
