"""Drive.start(omega0, i0) (motor/drive.py): the electrical steady state at a non-zero current
and speed, held against 4.162 with di/dt = 0 written here, and what follows from it: a
voltage-mode step at that voltage and speed keeps the current, a current-mode step asked for
i0 with i0 observed applies that voltage again, and LuGre's bristles start at rest.  Also the
noise seed's and instance's range, at its end."""
from __future__ import annotations

import pytest

from motor import Drive, friction, get_motor_preset

OMEGA0, I0 = 37.5, -0.625


@pytest.mark.parametrize("motor", ["motor1", "motor2"])
def test_start_is_the_electrical_steady_state_at_a_nonzero_current_and_speed(motor):
    """Catches a start voltage that drops the resistive drop R i0 or the back-emf ke omega0
    (both are zero by default, so a start at rest cannot tell), or a current not set."""
    params = get_motor_preset(motor)
    v0 = params.R * I0 + params.ke * OMEGA0
    drive = Drive(params, mode="voltage")
    drive.start(OMEGA0, I0)
    assert (drive.i, drive.v) == (I0, pytest.approx(v0, rel=1e-15))
    _, v, i = drive.step(0.0, drive.v, OMEGA0, I0, 1e-4)
    assert v == drive.v and i == pytest.approx(I0, rel=1e-9)
    current = Drive(params, mode="current")
    current.start(OMEGA0, I0)
    _, v, i = current.step(I0, 0.0, OMEGA0, I0, current.T)
    assert v == pytest.approx(v0, rel=1e-12) and i == pytest.approx(I0, rel=1e-9)


def test_a_lugre_drive_starts_with_its_bristles_at_their_steady_deflection():
    """Catches the bristles started at zero (or at another speed's deflection) for a spinning start."""
    drive = Drive(get_motor_preset("motor1"), mode="voltage", friction="lugre")
    drive.start(OMEGA0, I0)
    assert drive.z == friction.steady_deflection(drive.lugre, OMEGA0) != 0.0
    assert friction.bristle_rate(drive.lugre, drive.z, OMEGA0) == pytest.approx(0.0, abs=1e-12 * OMEGA0)


@pytest.mark.parametrize("name", ["noise_seed", "noise_instance"])
def test_the_noise_seed_and_instance_end_where_a_double_stops_holding_whole_numbers(name):
    """Catches a noise seed or instance accepted past 2**53 (the drive's buffer holds it as a
    double: 2**53 + 1 would become 2**53, another noise) or refused below it, and a message
    naming another limit."""
    params = get_motor_preset("motor1")
    Drive(params, current_noise=0.01, **{name: 2 ** 53 - 1})           # the largest: accepted
    with pytest.raises(ValueError) as caught:
        Drive(params, current_noise=0.01, **{name: 2 ** 53})
    assert str(caught.value) == f"{name} must be a whole number in [0, 9007199254740992), got 9007199254740992"
