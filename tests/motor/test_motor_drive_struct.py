"""The DC drive's C struct (``pc_drive``, kernels/src/drive.h) as :class:`motor.Drive` fills
it: every word read back exactly as drive.h documents it.  The native FMU adapter fills the
same struct on its own (fmus/native/adapters/pcn_drive_setup.c: ``current_mode = mode == 0``,
``mean_torque = torque == 1``), so an encoding drive.h does not document would make the two
structs of one drive differ even where drive.c reads only ``!= 0.0``."""
from __future__ import annotations

import math

import numpy as np
import pytest

from motor import Drive, kernel, motor1, motor2
from motor.current_controller import CurrentController, design_current_controller

FIELDS = kernel.indices(kernel.DRIVE)
CONTROLLER = kernel.CONTROLLER


@pytest.mark.parametrize("mode", ["current", "voltage"])
@pytest.mark.parametrize("torque_output", ["end", "mean"])
def test_the_drives_mode_and_torque_flags_are_1_or_0_as_drive_h_documents(mode, torque_output):
    """drive.h: ``current_mode`` 1 for K(z) on i_ref, 0 for voltage mode; ``mean_torque`` 1 for
    tau over the step's mean current, 0 at the step's end."""
    d = Drive(motor1, mode=mode, torque_output=torque_output)
    assert d.buf[FIELDS["current_mode"]] == (1.0 if mode == "current" else 0.0)
    assert d.buf[FIELDS["mean_torque"]] == (1.0 if torque_output == "mean" else 0.0)


def test_the_drives_constants_are_its_parameters_and_options_word_for_word():
    """B.2's constants are the motor's, the period, phase and imperfections the options given,
    the PWM quantum v_max / pwm_counts, and no step prepared (h NaN) before prepare_step."""
    p = motor2
    d = Drive(p, T=2e-3, pwm_counts=7, current_offset=0.03, current_noise=0.002, noise_seed=11,
              noise_instance=5, sample_phase=3)
    b = d.buf
    for name in ("ke", "kt", "b", "mu", "omega_eps", "v_max"):
        assert b[FIELDS[name]] == getattr(p, name), name
    assert b[FIELDS["T"]] == 2e-3
    assert b[FIELDS["sample_phase"]] == 3.0
    assert math.isnan(b[FIELDS["h"]])
    assert b[FIELDS["pwm_quantum"]] == p.v_max / 7
    assert (b[FIELDS["i_offset"]], b[FIELDS["i_noise"]]) == (0.03, 0.002)
    assert (b[FIELDS["noise_seed"]], b[FIELDS["noise_instance"]]) == (11.0, 5.0)
    # The ideal drive: no quantum, offset or noise (0 is "ideal" in drive.h).
    ideal = Drive(p).buf
    for name in ("pwm_quantum", "i_offset", "i_noise", "noise_seed", "noise_instance", "sample_phase"):
        assert ideal[FIELDS[name]] == 0.0, name


def test_the_controllers_struct_holds_its_design_and_restarts_saturated_with_zero_error():
    """``pc_controller`` (drive.h): alpha..delta the design's, v_max the saturation; a reset to
    v0 holds v0 clipped to +-v_max as both past outputs and zero as both past errors (the
    bumpless start); the voltage-mode drive's idle controller has zero coefficients."""
    design = design_current_controller(motor1)
    c = CurrentController(design, 12.0)
    for name in ("alpha", "beta", "gamma", "delta"):
        assert c.buf[CONTROLLER[name]] == getattr(design, name), name
    assert c.buf[CONTROLLER["v_max"]] == 12.0
    for v0, held in ((5.0, 5.0), (30.0, 12.0), (-30.0, -12.0)):
        c.buf[CONTROLLER["e1"]] = c.buf[CONTROLLER["e2"]] = 1.0
        c.reset(v0)
        assert (c.buf[CONTROLLER["u1"]], c.buf[CONTROLLER["u2"]]) == (held, held)
        assert (c.buf[CONTROLLER["e1"]], c.buf[CONTROLLER["e2"]]) == (0.0, 0.0)
    idle = CurrentController.idle_buffer(7.5)
    assert idle[CONTROLLER["v_max"]] == 7.5
    assert all(idle[CONTROLLER[name]] == 0.0 for name in ("alpha", "beta", "gamma", "delta", "u1", "u2", "e1", "e2"))


@pytest.mark.parametrize("mode", ["current", "voltage"])
def test_a_sample_undone_by_restoring_the_state_is_taken_again_the_same(mode):
    """A plant that samples the voltages and then refuses its step puts the drives back
    (``restore_controller_state``) and retries.  Undone on a drive's first step (no step length
    prepared in the state restored) and on a step that changed h, the same sample again gives
    the same voltage and buffers as the first time.  Catches a drive whose kept step length
    says "prepared" while its restored buffer is not (the sample then refused, for ever)."""
    drive, twin = Drive(motor1, mode=mode), Drive(motor1, mode=mode)
    for h in (1e-3, 5e-4):          # the first step, then one that changes h (at a period start: T = 1 ms)
        kept = drive.controller_state()
        first = drive.sample_voltage(0.5, 1.0, 0.1, h)
        drive.restore_controller_state(kept)
        assert drive.sample_voltage(0.5, 1.0, 0.1, h) == first == twin.sample_voltage(0.5, 1.0, 0.1, h)
        assert np.array_equal(drive.buf, twin.buf, equal_nan=True)
        assert np.array_equal(drive._controller_buf, twin._controller_buf, equal_nan=True)
