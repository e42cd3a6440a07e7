"""The Derivator FMU's parameter and input bounds at their edges (fmus/slaves/parcosim_derivator.py):
each bound met exactly (on the side its message states) and passed by the next double, the
refusal naming the variable, value and bound word for word; of two bad inputs, the first
one that is out of bounds is named.
"""
from __future__ import annotations

import math

import pytest

from fmus.slave.base import MIN_STEP
from fmus.slave.refusals import ABSURD
from fmus.slaves.parcosim_derivator import MIN_FC_T
from tests.fmus.slave.test_extremes import make_slave

T = 2e-3
NYQUIST = 0.5 / T
LOWEST = MIN_FC_T / T


def _refusal(parameters: dict) -> str:
    return make_slave("Derivator", {"T": T, **parameters}).error


@pytest.mark.parametrize("name", ["fc_vel", "fc_acc"])
def test_a_cutoff_must_be_below_nyquist_and_not_below_the_lowest(name):
    """'must be below 1/(2T)': 1/(2T) itself refused, the double under it taken; the lowest
    cutoff MIN_FC_T/T taken, the double under it refused.  Catches either comparison off by
    its equality, or the bounds computed from another T."""
    other = "fc_acc" if name == "fc_vel" else "fc_vel"
    others = {other: 10.0}
    assert _refusal({name: NYQUIST, **others}) == (f"initialisation refused: parameter {name} = {NYQUIST!r} Hz must "
                                                   f"be below 1/(2T) = {NYQUIST:g} Hz (t = 0 s)")
    assert make_slave("Derivator", {"T": T, name: math.nextafter(NYQUIST, 0.0), **others})._ready
    below = math.nextafter(LOWEST, 0.0)
    assert _refusal({name: below, **others}) == (
        f"initialisation refused: parameter {name} = {below!r} Hz is below {MIN_FC_T:g}/T = {LOWEST:g} Hz: the filter "
        f"discretised at T = {T!r} s would be singular (t = 0 s)")
    edge = make_slave("Derivator", {"T": T, name: LOWEST, **others})
    assert edge._ready or "is below" not in edge.error


def test_the_sample_time_may_be_the_shortest_step_and_not_less():
    """Catches the MIN_STEP floor off by its equality."""
    fc = {"fc_vel": 1e5, "fc_acc": 5e4}     # within ABSURD, above MIN_FC_T / MIN_STEP
    assert make_slave("Derivator", {"T": MIN_STEP, **fc})._ready
    short = math.nextafter(MIN_STEP, 0.0)
    assert make_slave("Derivator", {"T": short, **fc}).error == (
        f"initialisation refused: parameter T = {short!r} s is below the shortest step {MIN_STEP:g} s (t = 0 s)")


def _step(q1: float, q2: float):
    slave = make_slave("Derivator", {"T": 1e-3})
    slave.q1, slave.q2 = q1, q2
    return slave.do_step(0.0, 1e-3), slave.error


def test_an_input_may_be_absurd_at_most_and_the_first_bad_one_is_named():
    """|q| = ABSURD is taken; the next double is refused as absurd; with q1 at the bound and
    q2 not finite, q2 is named.  Catches the absurd check off by its equality, and an input
    at the bound named in another's place."""
    assert _step(ABSURD, -ABSURD)[0] is not False
    over = math.nextafter(ABSURD, math.inf)
    assert _step(1.0, -over) == (False, f"input q2 = {-over!r} rad at t = 0 s is absurd: |q2| must be <= {ABSURD:g} rad")
    assert _step(ABSURD, math.nan) == (False, "input q2 = nan at t = 0 s is not finite")
    assert _step(math.inf, over) == (False, "input q1 = inf at t = 0 s is not finite")
