"""IntegratorSettings: its defaults are docs/plant.md's table, and each refusal of
``validate`` names the setting and its value, at the boundaries themselves (0 for rtol, atol
and baumgarte)."""
from __future__ import annotations

import math

import pytest

import plant
from plant.simulator import IntegratorSettings


def test_the_defaults_are_the_documented_ones():
    """docs/plant.md "Settings and accuracy": rk4, 1 substep, rtol 1e-10, atol 1e-13,
    baumgarte 10 /s, no projection, the fast kernel; plant.ACCURATE is dopri5 at 1e-12, 1e-15."""
    s = IntegratorSettings()
    assert (s.method, s.substeps, s.rtol, s.atol, s.baumgarte, s.project, s.kernel) == (
        "rk4", 1, 1e-10, 1e-13, 10.0, False, "fast")
    a = plant.ACCURATE
    assert (a.method, a.rtol, a.atol) == ("dopri5", 1e-12, 1e-15)


@pytest.mark.parametrize("change, message", [
    (dict(method="euler"), "method: unknown integrator 'euler'; valid: rk4, dopri5"),
    (dict(kernel="c"), "kernel: unknown kernel 'c'; valid: fast, general"),
    (dict(rtol=0.0), "rtol must be > 0, got 0.0"),
    (dict(atol=0.0), "atol must be > 0, got 0.0"),
    (dict(rtol=math.inf), "rtol must be > 0, got inf"),
    (dict(atol=math.nan), "atol must be > 0, got nan"),
    (dict(baumgarte=-1e-300), "baumgarte must be >= 0, got -1e-300"),
    (dict(baumgarte=math.inf), "baumgarte must be >= 0, got inf"),
    (dict(baumgarte=math.nan), "baumgarte must be >= 0, got nan"),
])
def test_each_refusal_names_the_setting_and_its_value_word_for_word(change, message):
    with pytest.raises(ValueError) as caught:
        IntegratorSettings(**change).validate()
    assert str(caught.value) == message


def test_the_smallest_tolerances_and_a_zero_baumgarte_are_accepted():
    """rtol, atol > 0 and baumgarte >= 0: the least positive double and 0 itself pass."""
    s = IntegratorSettings(method="dopri5", rtol=5e-324, atol=5e-324, baumgarte=0.0)
    assert s.validate() is s
