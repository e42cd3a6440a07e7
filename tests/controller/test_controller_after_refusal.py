"""A refused sample of the position law leaves nothing behind: the samples after it are, bit for
bit, those of a controller that never saw it (controller/position.py: "The law's state is
unchanged"), whatever the refusal wrote into the kernel's scratch."""
from __future__ import annotations

import math

import pytest

import kernels
from controller.position import PositionController
from controller.strategies import get_strategy
from plant import fivebar, get_preset

BENCH = get_preset("bench")


def _samples(n):
    """Measured angles of a point near (x, y) moving, with a reference 1 mm off, as the 12 inputs."""
    for k in range(n):
        x, y = 0.01 + 2e-3 * k, 0.15 - 1e-3 * k
        ang = fivebar.inverse_kinematics(BENCH, x, y)
        yield [ang[0], ang[2], 0.3, -0.2, 1.0, 0.5, x + 1e-3, y, 0.1, 0.2, -1.0, 0.5]


@pytest.mark.parametrize("strategy", ["PDx", "TCMDx", "TCq"])
@pytest.mark.parametrize("refusal, reason", [(dict(dq1=1e308), "NONFINITE_OUTPUT"), (dict(dq2=math.nan), "NONFINITE"),
                                             (dict(x_d=0.5, y_d=0.1), "REF_OUT")])
def test_the_samples_after_a_refused_one_are_those_of_a_controller_that_never_saw_it(strategy, refusal, reason):
    """Catches a law that keeps anything of a refused sample: its state, or a check that reads
    the scratch the refused sample wrote (the outputs it overflowed into, just after the 12
    inputs: an input check running one entry too far refuses every later sample)."""
    refused, clean = (PositionController(BENCH, get_strategy(strategy), model="exact") for _ in range(2))
    samples = list(_samples(6))
    for k, values in enumerate(samples):
        if k == 2:
            bad = dict(zip(("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d"),
                           values), **refusal)
            with pytest.raises(kernels.Refused) as caught:
                refused.step_with_errors(k * 1e-3, *bad.values())
            assert caught.value.reason == reason
        assert refused.step_with_errors(k * 1e-3, *values) == clean.step_with_errors(k * 1e-3, *values), k
        assert (refused.integral, refused.k, refused.s, refused.e) == (clean.integral, clean.k, clean.s, clean.e)
