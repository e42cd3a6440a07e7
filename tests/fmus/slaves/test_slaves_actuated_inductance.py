"""ActuatedFiveBarPlant's own refusals of its drives' inductances and of its sample time
(issue 31; session 43's training seed 4322 [12] in fmus/slaves/parcosim_actuatedfivebarplant.py):
L1, L2 must be > 0 (the drives inside integrate the armature current) unless -1 (the preset's
value), refused from 0 up to TINY and accepted from TINY on; T below MIN_STEP is refused."""
from __future__ import annotations

import pytest

from fmus.slave.base import MIN_STEP
from fmus.slave.refusals import PRESET_VALUE, TINY
from motor import get_motor_preset
from tests.fmus.slave.test_extremes import make_slave

MODEL = "ActuatedFiveBarPlant"


@pytest.mark.parametrize("j", [1, 2])
def test_an_inductance_is_accepted_at_its_presets_value_at_tiny_and_at_minus_1(j):
    """L{j} given explicitly as the preset motor's own L, as TINY (the floor itself) and as -1:
    initialisation accepts each.  Catches the refusal of L widened to every value given."""
    for value in (get_motor_preset(f"motor{j}").L, TINY, PRESET_VALUE):
        slave = make_slave(MODEL, {f"L{j}": value})
        assert slave.error == "" and slave._ready, (value, slave.error)


@pytest.mark.parametrize("j", [1, 2])
@pytest.mark.parametrize("value", [0.0, TINY / 2])
def test_an_inductance_from_zero_up_to_tiny_is_refused_naming_it(j, value):
    """L{j} = 0 and TINY / 2: refused with the variable, its value and why, word for word."""
    slave = make_slave(MODEL, {f"L{j}": value})
    assert slave.error == (f"initialisation refused: parameter L{j} = {value!r} H must be > 0: the drives inside the "
                           "plant integrate the armature current (use a separate DCMotorDrive with method "
                           "'quasi_static' for L = 0) (t = 0 s)")


def test_a_sample_time_below_the_shortest_step_is_refused_naming_it():
    """T = MIN_STEP / 2 refused naming T and the floor; T = MIN_STEP is not refused for it."""
    slave = make_slave(MODEL, {"T": MIN_STEP / 2})
    assert slave.error == f"initialisation refused: parameter T = {MIN_STEP / 2!r} s must be >= {MIN_STEP:g} s (t = 0 s)"
    assert "must be >= " not in make_slave(MODEL, {"T": MIN_STEP}).error
