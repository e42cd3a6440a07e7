"""scenarios/scenes/perturb.py at its boundaries, hit exactly (issue 31, session 44: the
refusals' and the truncation's edges of the generalised training sample)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from scenarios.scenes import perturb
from scenarios.scenes.perturb import TRUNCATE_SIGMA, load_perturb_file


class _Normal:
    """A generator whose standard normal draws are the given values, in order."""

    def __init__(self, values):
        self.values = list(values)

    def standard_normal(self):
        return self.values.pop(0)


def test_the_normal_draw_is_truncated_at_three_sigma_inclusive(monkeypatch):
    """"standard normal truncated at +-3": a draw of exactly +-3 is kept, one a float beyond is
    drawn again (the next value is the draw).  Catches the bound made exclusive or moved."""
    assert TRUNCATE_SIGMA == 3.0
    beyond = math.nextafter(3.0, math.inf)
    for drawn, expected in (([beyond, 3.0, 0.25], 3.0), ([-beyond, -3.0, 0.25], -3.0),
                            ([beyond, -beyond, 2.5], 2.5)):
        monkeypatch.setattr(np.random, "default_rng", lambda sequence, d=list(drawn): _Normal(d))
        assert perturb._xi(1, 2, "drive1.R", "normal") == expected


def test_a_perturb_file_uncertainty_of_exactly_zero_is_accepted_and_keeps_the_parameter_nominal(tmp_path):
    """The module docstring: "0 keeps it nominal" -- a zero (int or float) is a valid entry,
    the smallest one (a value just below it is refused, naming file and key)."""
    f = tmp_path / "p.toml"
    f.write_text('[uncertainty]\n"drive1.R" = 0\n"drive2.*" = 0.0\n')
    assert load_perturb_file(f) == {"uncertainty": {"drive1.R": 0.0, "drive2.*": 0.0}, "distribution": None}
    f.write_text('[uncertainty]\n"drive1.R" = -5e-324\n')
    with pytest.raises(ValueError, match=rf"--perturb {f}: uncertainty 'drive1.R' = -5e-324 must be a finite number >= 0"):
        load_perturb_file(f)


def test_an_uncertainty_u_just_below_zero_is_refused_and_zero_accepted():
    """``uncertainties``' refusal at its edge: the smallest negative float is refused naming U,
    0 and the smallest positive float accepted."""
    params = [perturb.Parameter("drive1.R", 1.0, "motor")]
    with pytest.raises(ValueError, match=r"uncertainty U = -5e-324 must be a finite number >= 0"):
        perturb.uncertainties(params, -5e-324)
    assert perturb.uncertainties(params, 0.0) == {"drive1.R": 0.0}
    assert perturb.uncertainties(params, 5e-324) == {"drive1.R": 5e-324}
