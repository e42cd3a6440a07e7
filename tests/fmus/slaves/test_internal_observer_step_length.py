"""A DCMotorDrive with its internal observer (``internal_observer``, current mode) is the drive
fed, at each step, the estimate of an observer outside it (motor.CurrentObserver) given the
voltage the drive applied over the step just taken, the speed now and the step's length h.
Run from t = 0.25 s, so the step's length and its time differ."""
from __future__ import annotations

import pytest

from fmus.slaves.parcosim_dcmotordrive import DCMotorDrive
from motor import CurrentObserver

T0, H = 0.25, 1e-3


def _drive(**parameters):
    drive = DCMotorDrive(instance_name="drive")
    drive.setup_experiment(T0, None, None)
    drive.enter_initialization_mode()
    for name, value in parameters.items():
        setattr(drive, name, value)
    drive.exit_initialization_mode()
    assert not drive.error, drive.error
    return drive


@pytest.mark.parametrize("kind", ["static", "dynamic"])
def test_the_internal_observer_is_the_outside_observer_at_the_steps_length(kind):
    inside = _drive(internal_observer=True, observer_kind=kind)
    outside = _drive()
    observer = CurrentObserver(inside.observer.params, kind)
    observer.reset(0.0, 0.0)
    for k in range(20):
        t = T0 + k * H
        omega = 3.0 + 0.5 * k
        for d in (inside, outside):
            d.i_ref, d.omega = 0.8, omega
        outside.i_hat = observer.estimate(outside.v, omega, H)
        inside.step(t, H)
        outside.step(t, H)
        assert (inside.tau, inside.v, inside.i) == (outside.tau, outside.v, outside.i), k
