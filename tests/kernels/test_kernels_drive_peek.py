"""``pc_drive_peek_voltage`` (kernels/src/drive.c), the exported C call the actuated plant's step
makes before it keeps a drive's sample: the ``pc_drive_sample`` it fills (drive.h: the voltage
applied, the controller's error at this sample, whether the controller sampled, the sub-step
after the step) read field by field in both modes, and nothing of the drive or its controller
changed by a peek.

Every field is read here, not only the voltage: the step paths keep a voltage-mode sample's
error unread (it is not sampled), so a wrong error or flag there shows only through this call
(training sample 4301 [16]).
"""
from __future__ import annotations

import copy
import ctypes

import numpy as np
import pytest

import kernels
from motor import Drive, motor1
from motor.current_controller import THESIS_T
from motor.drive import gaussian

_p, _d = ctypes.c_void_p, ctypes.c_double
_peek = kernels.function("pc_drive_peek_voltage", ctypes.c_int, _p, _p, _d, _d, _d, _d, _p, _p)


class Sample(ctypes.Structure):
    """``pc_drive_sample`` of drive.h, its fields in the header's order."""

    _fields_ = [("v", _d), ("e", _d), ("sampled", _d), ("phase", _d)]


def peek(drive, i_ref, v_ref, i_hat, h):
    """(code, sample, refusal) of one peek on the drive's own buffers."""
    sample, refusal = Sample(), kernels.Refusal()
    code = _peek(kernels.address(drive.buf), kernels.address(drive._controller_buf), i_ref, v_ref, i_hat, h,
                 ctypes.byref(sample), ctypes.byref(refusal))
    return code, sample, refusal


def buffers(drive):
    return drive.buf.copy(), drive._controller_buf.copy()


@pytest.mark.parametrize("v_ref", [0.37 * motor1.v_max, -2.0 * motor1.v_max])
@pytest.mark.parametrize("counts", [0, 200])
def test_a_voltage_mode_peek_is_the_saturated_quantised_reference_and_no_controller_sample(v_ref, counts):
    """Voltage mode: v is v_ref saturated at +-v_max, then the PWM's nearest multiple of
    v_max / counts (none for counts 0); no controller sample, so the error is 0, the flag 0 and
    the sub-step unchanged; the drive and its (idle) controller are not written."""
    h = 1e-3
    drive = Drive(motor1, mode="voltage", pwm_counts=counts)
    drive.prepare_step(h)
    drive.reset(0.2, 1.0)
    before = buffers(drive)
    code, s, _ = peek(drive, 0.7, v_ref, 0.3, h)
    assert code == 0
    v = float(np.clip(v_ref, -motor1.v_max, motor1.v_max))
    if counts:
        q = motor1.v_max / counts
        v = round(v / q) * q        # no tie at these references
    assert s.v == pytest.approx(v, rel=1e-12)
    assert (s.e, s.sampled, s.phase) == (0.0, 0.0, drive.substep)
    for kept, now in zip(before, buffers(drive)):
        np.testing.assert_array_equal(kept, now)


def test_a_current_mode_peek_on_its_sample_step_reads_the_offset_and_noisy_current():
    """Current mode at h = T / 4, sample phase 0, with a current offset and noise: at the sample
    step the error is i_ref minus the measured current (i_hat + offset + noise of the drive's
    (seed, instance, sample 0)), v the controller's update on that error (pc_controller_update
    on a copy), the flag 1 and the sub-step 1; nothing is kept, and the next sample_voltage
    applies the same v."""
    h, offset, noise, seed, instance = THESIS_T / 4, 0.05, 0.02, 7, 3
    drive = Drive(motor1, current_offset=offset, current_noise=noise, noise_seed=seed, noise_instance=instance)
    drive.prepare_step(h)
    drive.reset(0.1, 0.4)
    before = buffers(drive)
    i_ref, i_hat = 0.9, 0.25
    measured = i_hat + offset + noise * gaussian(seed, instance, 0)
    expected_v = copy.deepcopy(drive).controller.update(i_ref, measured)
    code, s, _ = peek(drive, i_ref, 0.0, i_hat, h)
    assert code == 0
    assert s.e == pytest.approx(i_ref - measured, rel=1e-14)
    assert s.v == pytest.approx(expected_v, rel=1e-12)
    assert (s.sampled, s.phase) == (1.0, 1.0)
    for kept, now in zip(before, buffers(drive)):
        np.testing.assert_array_equal(kept, now)
    assert drive.sample_voltage(i_ref, 0.0, i_hat, h) == s.v


def test_a_current_mode_peek_between_samples_holds_the_last_voltage_and_counts_the_sub_step():
    """Between two controller samples (sub-step 1 of 4) the drive applies the voltage it holds:
    no sample (flag 0), v the drive's v whatever the inputs, the sub-step counted on to 2."""
    h = THESIS_T / 4
    drive = Drive(motor1)
    drive.prepare_step(h)
    drive.reset(0.0, 0.0)
    drive.sample_voltage(0.5, 0.0, 0.0, h)      # the sample of sub-step 0
    drive.v = 1.25                              # what the caller applied (sample_voltage leaves v to it)
    assert drive.substep == 1
    code, s, _ = peek(drive, 3.0, -4.0, -1.0, h)
    assert code == 0
    assert (s.v, s.sampled, s.phase) == (1.25, 0.0, 2.0)


@pytest.mark.parametrize("mode", ["voltage", "current"])
@pytest.mark.parametrize("index, name", [(1, "i_ref"), (2, "v_ref"), (3, "i_hat")])
def test_a_peek_refuses_a_non_finite_input_by_its_index_and_a_step_not_prepared(mode, index, name):
    """A non-finite input is refused with NONFINITE_INPUT, its index in drive.h's list (omega 0,
    not an input of a peek, then i_ref, v_ref, i_hat) and its value; a step length other than
    the prepared one with UNPREPARED_STEP and that length."""
    h = THESIS_T / 2
    drive = Drive(motor1, mode=mode)
    drive.prepare_step(h)
    values = {"i_ref": 0.1, "v_ref": 0.2, "i_hat": 0.3}
    values[name] = float("inf")
    code, _, r = peek(drive, values["i_ref"], values["v_ref"], values["i_hat"], h)
    assert (code, r.code, r.index, r.value) == (1, 1, index, float("inf"))
    code, _, r = peek(drive, 0.1, 0.2, 0.3, h / 2)
    assert (code, r.code, r.index, r.value) == (2, 2, 0, h / 2)
