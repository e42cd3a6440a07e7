"""Each parameter set through an FMU's variables reaches the model it names (fmus/slave/declarations.py):
the plant's mechanism, integrator and encoders, and each drive's motor, design and options,
compared with the same models built directly from plant and motor (an independent route: the
presets with the values replaced, no FMU code).  Every value differs from its default and, where
there are two (chains, drives), from the other's, so a parameter dropped, swapped between chain 1
and 2 or drive 1 and 2, or given to the design instead of the motor shows (issue 31: zero-by-default
and second values; ``CLI options actually taking effect`` for the FMU's parameters).  In process."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from motor import Drive, get_motor_preset
from plant import IntegratorSettings, get_preset
from tests.fmus.slave.test_extremes import X1, make_slave

PLANT = {"preset": "bench", "x0": X1[0], "y0": X1[1], "J_rotor1": 2.5e-5, "J_rotor2": 3.5e-5, "l0": 0.051,
         "gravity_x": 0.3, "gravity_y": -9.81, "gravity_z": 1.0, "link_inertias": False, "encoder_counts": 4000,
         "chain1_l1": 0.101, "chain1_lg2": 0.07, "chain2_m2": 0.07, "chain2_lg1": 0.03, "chain2_Jz2": 1e-4,
         "encoder_offset1": 1e-3, "encoder_offset2": -2e-3, "substeps": 3, "baumgarte": 7.0, "rtol": 1e-7,
         "atol": 1e-9, "project": False}


def test_the_plants_parameters_reach_its_mechanism_integrator_and_encoders():
    """The FiveBarPlant's simulator against the bench preset with the same values put in by
    hand: rotors, chain overrides (each on its own chain), base half-distance, gravity, link
    inertias off, the integrator's settings, the encoders' count and offsets."""
    slave = make_slave("FiveBarPlant", PLANT)
    assert slave.error == ""
    preset = get_preset("bench").with_rotors(2.5e-5, 3.5e-5)
    chain1 = replace(preset.chain1, l1=0.101, lg2=0.07, Jz1=0.0, Jz2=0.0)
    chain2 = replace(preset.chain2, m2=0.07, lg1=0.03, Jz1=0.0, Jz2=0.0)     # link_inertias off: Jz2 too
    expected = replace(preset, chain1=chain1, chain2=chain2, l0=0.051, m0=0.0, gravity=(0.3, -9.81, 1.0))
    sim = slave.sim
    assert sim.params == expected
    assert sim.settings == IntegratorSettings(method="rk4", substeps=3, rtol=1e-7, atol=1e-9, baumgarte=7.0,
                                              project=False, kernel="fast")
    assert (sim.encoder_counts, sim.encoder_offsets) == (4000, (1e-3, -2e-3))
    assert (slave.x, slave.y) == pytest.approx(X1, abs=1e-12)


def _same_drive(drive, reference) -> None:
    assert drive.params == reference.params
    np.testing.assert_array_equal(drive.buf, reference.buf)
    np.testing.assert_array_equal(drive.controller.buf, reference.controller.buf)


def test_a_drives_motor_design_and_options_reach_its_drive():
    """DCMotorDrive with a changed motor (R, kt, b), a changed design (R_design, L_design) and its
    options (PWM, current offset and noise, the noise's seed and instance, LuGre friction)
    against motor.Drive built from the motor1 preset directly: the same constants, controller
    coefficients and state."""
    values = {"R": 1.2, "kt": 0.05, "b": 2e-4, "R_design": 1.0, "L_design": 7e-4, "pwm_counts": 100,
              "current_offset": 0.01, "current_noise": 0.002, "noise_seed": 5, "noise_instance": 2,
              "friction": "lugre"}
    slave = make_slave("DCMotorDrive", values)
    assert slave.error == ""
    motor = get_motor_preset("motor1").with_(R=1.2, kt=0.05, b=2e-4)
    reference = Drive(motor, design_params=motor.with_(R=1.0, L=7e-4), friction="lugre", pwm_counts=100,
                      current_offset=0.01, current_noise=0.002, noise_seed=5, noise_instance=2)
    _same_drive(slave.drive, reference)


def test_each_drive_of_the_actuated_plant_gets_its_own_parameters():
    """ActuatedFiveBarPlant's two drives with different motor values, designs and options (drive
    1 given motor 2's preset too): drive 1 is motor.Drive of its own values, drive 2 of its own
    (none swapped or shared)."""
    values = {"preset": "bench", "x0": X1[0], "y0": X1[1], "preset1": "motor2", "R2": 1.2, "kt1": 0.05,
              "R_design2": 1.0, "pwm_counts1": 100, "current_offset2": 0.01, "friction2": "lugre",
              "noise_instance1": 3}
    slave = make_slave("ActuatedFiveBarPlant", values)
    assert slave.error == ""
    first = get_motor_preset("motor2").with_(kt=0.05)          # drive 1's preset changed to motor 2's
    second = get_motor_preset("motor2").with_(R=1.2)           # drive 2's own default
    drive1, drive2 = slave.current_loops()
    _same_drive(drive1, Drive(first, pwm_counts=100, noise_instance=3))
    _same_drive(drive2, Drive(second, design_params=second.with_(R=1.0), current_offset=0.01, friction="lugre"))
