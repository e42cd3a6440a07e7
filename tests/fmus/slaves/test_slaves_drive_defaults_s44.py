"""A drive slave left at its defaults is :class:`motor.Drive` at its documented defaults (issue 31,
training seed 4441 [7]: ``DRIVE_OPTIONS``' ``pwm_counts`` start 0 -> 1 passed every quick test; a start
is a module-level constant no test executed by itself).

docs/motor.md: the bench's PWM resolution and the current loop's reading errors are "off by default";
the drive's preset is ``motor1``, its mode ``current``, its method ``exact``, its friction ``tanh``.  The
slave in process is stepped beside a :class:`motor.Drive` built here from those words alone, and every
output compared bit for bit; the noise's seed and instance (which matter only with a noise on) with a noise
set on both, so each default reaches an observable.
"""
from __future__ import annotations

import pytest

from fmus.cosim.backends import InProcessInstance
from motor import Drive, get_motor_preset

H = 1e-3
#: (i_ref, v_ref, omega, i_hat) per step: a current reference that changes, a held voltage, a speed.
INPUTS = [(0.3, 3.0, 0.0, 0.0), (0.3, 3.0, 2.0, 0.25), (-0.2, 7.5, 5.0, 0.31), (0.1, -4.0, -1.0, -0.1),
          (0.1, 30.0, 0.5, 0.05)]


def _slave_rows(model: str, values: dict, suffix: str = "") -> list:
    instance = InProcessInstance(model, "d")
    instance.initialize(values, 0.0)
    slave = instance.slave
    assert not slave.error, slave.error
    rows = []
    for k, (i_ref, v_ref, omega, i_hat) in enumerate(INPUTS):
        for name, value in (("i_ref", i_ref), ("v_ref", v_ref), ("omega", omega), ("i_hat", i_hat)):
            setattr(slave, name + suffix, value)
        assert slave.do_step(k * H, H)
        rows.append((slave.tau, slave.v, slave.i))
    return rows


def _drive_rows(**options) -> list:
    drive = Drive(get_motor_preset("motor1"), T=1e-3, **options)
    drive.start(0.0, 0.0)
    return [drive.step(i_ref, v_ref, omega, i_hat, H) for i_ref, v_ref, omega, i_hat in INPUTS]


@pytest.mark.parametrize("mode", ["current", "voltage"])
def test_a_default_drive_slave_is_the_ideal_motor1_drive_bit_for_bit(mode):
    """Catches a default PWM quantisation, current offset or noise switched on (the voltage mode then
    applies a multiple of v_max instead of 3 V), another preset, method or friction."""
    assert _slave_rows("DCMotorDrive", {"mode": mode}) == _drive_rows(mode=mode)


def test_the_voltage_mode_applies_the_commanded_voltage_exactly_by_default():
    """docs/motor.md: PWM is off by default, so the applied voltage is v_ref itself (saturated at
    v_max = 24 V), not a multiple of a PWM quantum."""
    applied = [v for _, v, _ in _slave_rows("DCMotorDrive", {"mode": "voltage"})]
    assert applied == [3.0, 3.0, 7.5, -4.0, 24.0]


def test_the_noise_of_a_default_drive_is_seed_0_instance_0():
    """Catches a default noise seed or instance off motor.Drive's (0, 0): with only the noise's size set, the
    drive slave reads the same noisy currents as the drive built with seed 0, instance 0, and not those of
    seed 1 or instance 1."""
    rows = _slave_rows("DCMotorDrive", {"current_noise": 0.05})
    assert rows == _drive_rows(current_noise=0.05, noise_seed=0, noise_instance=0)
    assert rows != _drive_rows(current_noise=0.05, noise_seed=1, noise_instance=0)
    assert rows != _drive_rows(current_noise=0.05, noise_seed=0, noise_instance=1)
