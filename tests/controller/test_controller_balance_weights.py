"""The balance design's weights (Bryson's rule) and the observer's noise levels
(controller/balance.py) against docs/pendulum.md, which states each value: the tests of the
design compute with the module's own constants, so only the text holds their values."""
import re
from pathlib import Path

import pytest

from controller import balance

DOC = " ".join((Path(__file__).resolve().parents[2] / "docs" / "pendulum.md").read_text().split())


def _number_after(pattern: str) -> float:
    m = re.search(pattern + r" ([0-9.e-]+)", DOC)
    assert m, pattern
    return float(m[1])


def test_the_bryson_weights_are_the_documented_largest_acceptable_excursions():
    m = re.search(r"Bryson weights: largest acceptable θ (\S+) rad, ψ (\S+) rad, φ (\S+) rad, θ̇ (\S+) rad/s, "
                  r"ψ̇ (\S+) rad/s, φ̇ (\S+) rad/s; voltage (\S+) V", DOC)
    assert m
    assert balance.STATE_SCALE == tuple(float(v) for v in m.groups()[:6])
    assert balance.VOLTAGE_SCALE == float(m[7])


@pytest.mark.parametrize("name, pattern", [("VOLTAGE_NOISE", r"voltage noise"),
                                           ("BODY_TORQUE_NOISE", r"body-torque noise"),
                                           ("GYRO_NOISE", r"body-torque noise \S+ N m, gyro")])
def test_the_observer_noise_levels_are_the_documented_ones(name, pattern):
    assert getattr(balance, name) == _number_after(pattern)
