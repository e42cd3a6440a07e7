"""The five-bar kernel's turned trigonometry (kernels/src/fivebar.c, trig_lanes_at): an RK4
stage's sines and cosines are turned from the step's start only when every angle of the stage
is within 2^-5 rad of the start's, whatever the angle itself.  Here the proximal angles
(theta_11, theta_21) sweep through 0 within one step, the companion of
test_kernels_fivebar.py's sweep of the elbow angles."""
from __future__ import annotations

import numpy as np
import pytest

from tests.kernels.test_kernels_fivebar import _swept_step


@pytest.mark.parametrize("start, rate", [(0.5, -48.0), (-0.5, 48.0), (0.3, -29.0)])
def test_stages_far_from_the_start_near_zero_proximal_angles_are_computed_afresh(start, rate):
    """Both proximal angles start at ``start`` and pass about 0 within one 20 ms step: the
    later stages sit near angle 0 but 0.25-0.5 rad from the step's start, far beyond the range of
    the turning series.  Catches a turn-or-fresh choice that looks at a proximal angle instead
    of its distance from the start (the series at 0.5 rad is off by about 1e-8): the trial
    equals RK4 of fresh derivatives to 1e-14 of max(1, |entry|)."""
    z, trial, fresh = _swept_step([3, 5], start, rate)
    assert np.all(np.isfinite(fresh))
    assert np.all(np.abs(trial - fresh) <= 1e-14 * np.maximum(np.abs(fresh), 1.0))
    assert np.abs(trial[[3, 5]] - z[[3, 5]]).min() > 0.25      # the stages did move that far
