"""The balance controller's refusal records (controller/balance.py's REASONS), word for word for
every code: the message, the reason, the variable the record names, its value, its unit ("": the
three inputs are readings of two units) and the time.  Two come through
:meth:`BalanceController.sample` itself; INPUT_LIMIT, which the controller's own sample never
meets (it samples with no limit: the slave refuses an absurd input first), comes from the
kernel's record of a sample with the slave's limit, and reads as the slave's own refusal does."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from controller import fastbalance
from controller.balance import REASONS, BalanceController, BalanceSettings, design_balance
from fmus.slave.refusals import ABSURD, refuse_absurd_inputs

T = 0.375


@pytest.fixture(scope="module")
def design():
    return design_balance(BalanceSettings(yaw=False))


def test_a_non_finite_input_is_refused_by_the_controller_word_for_word(design):
    """Catches a not-finite message that drops a field or its explanation, names another input
    (an index off by one in INPUTS) or carries a unit, reason or time of another code."""
    for index, name in enumerate(fastbalance.INPUTS):
        inputs = [0.0, 0.0, 0.0]
        inputs[index] = -math.inf
        with pytest.raises(kernels.Refused) as caught:
            BalanceController(design).sample(T, *inputs)
        assert str(caught.value) == f"input {name} = -inf at t = 0.375 s is not finite"
        assert caught.value.record() == {"instance": None, "time": T, "variable": name, "value": -math.inf,
                                         "unit": "", "code": fastbalance.BAD_INPUT, "reason": "input_not_finite",
                                         "message": str(caught.value)}
        assert caught.value.names_time


def test_a_damaged_buffer_word_is_refused_by_the_controller_word_for_word(design):
    """Catches a damaged-buffer message that drops a field or its explanation, or names another
    word of the buffer than the one the kernel refused."""
    controller = BalanceController(design)
    index = fastbalance.BUFFER["ny"].start
    controller.buf[index] = 4.0                          # one past the largest output count
    with pytest.raises(kernels.Refused) as caught:
        controller.sample(T, 0.0, 0.0, 0.0)
    assert str(caught.value) == ("the balance controller's buffer word ny = 4.0 at t = 0.375 s is not a size or "
                                 "state index its arrays have")
    assert caught.value.record() == {"instance": None, "time": T, "variable": "ny", "value": 4.0, "unit": "",
                                     "code": fastbalance.BAD_BUFFER, "reason": "bad_buffer",
                                     "message": str(caught.value)}


@pytest.mark.parametrize("index", [0, 1, 2])
def test_an_absurd_input_reads_as_the_slaves_own_refusal_of_it(design, index):
    """The kernel's INPUT_LIMIT record under REASONS is the sentence the slave's
    refuse_absurd_inputs gives for the same input, value and time (and the C FMU's).  Catches
    an absurd-input reason whose template and unit are swapped (an empty message), or whose
    message names another input or limit."""
    buf, x, refusal = BalanceController(design).buf.copy(), np.zeros(fastbalance.IO_SIZE), kernels.Refusal()
    x[index] = -2.5 * ABSURD
    assert fastbalance.sample(buf, x, T, ABSURD, refusal) == fastbalance.INPUT_LIMIT
    refused = kernels.refused(REASONS, refusal, T, limit=ABSURD)
    name = fastbalance.INPUTS[index]
    with pytest.raises(ValueError) as slave:
        refuse_absurd_inputs(T, **{name: float(x[index])})   # the slave reads floats
    assert str(refused) == str(slave.value) == f"input {name} = -2500000.0 at t = 0.375 s is absurd: |{name}| " \
                                               "must be <= 1e+06"
    assert refused.record() == {"instance": None, "time": T, "variable": name, "value": -2.5e6, "unit": "",
                                "code": fastbalance.INPUT_LIMIT, "reason": "input_absurd", "message": str(refused)}
    assert refused.names_time


def test_every_balance_reason_is_named_for_its_code_and_names_the_time():
    """Catches two codes sharing a reason name (a record that cannot tell them apart) or a
    template without the time (a refusal the FMU layer would have to time itself)."""
    names = {code: reason.name for code, reason in REASONS.items()}
    assert names == {fastbalance.BAD_INPUT: "input_not_finite", fastbalance.INPUT_LIMIT: "input_absurd",
                     fastbalance.BAD_BUFFER: "bad_buffer"}
    assert all({"variable", "value", "time"} <= reason.fields for reason in REASONS.values())
