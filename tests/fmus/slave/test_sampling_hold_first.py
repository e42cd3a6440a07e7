"""``hold_first_step`` (fmus/slave/sampling.py, docs/ssp.md): the run's first step, the one from
fmi2SetupExperiment's start time, does not sample whatever its phase; the outputs hold their
start values over it and the first sample is the phase's next (issue 31; training seed 4361's
generalisation: a Boolean parameter whose true value no fmus/slave test set)."""
from __future__ import annotations

import numpy as np
import pytest

from tests.fmus.slave.test_extremes import slave_class
from tests.fmus.slave.test_sampling_phase import SAMPLED, T, input_value, new_slave


def _rows(model, n, t0, hold, periods=3):
    """Outputs after initialisation, then after each step of h = T / n from ``t0``."""
    _, inputs, outputs = SAMPLED[model]
    slave = new_slave(model, {"hold_first_step": hold}, t0=t0)
    rows, h = [[getattr(slave, name) for name in outputs]], T / n
    for k in range(periods * n):
        m, j = divmod(k, n)
        for index, (name, (base, amplitude)) in enumerate(inputs.items()):
            setattr(slave, name, input_value(base, amplitude, m, j, index))
        assert slave.do_step(t0 + k * h, h), slave.error
        rows.append([getattr(slave, name) for name in outputs])
    return np.array(rows)


@pytest.mark.parametrize("model", SAMPLED)
@pytest.mark.parametrize("n, t0", [(1, 0.0), (4, 0.0), (1, 1.5)])
def test_hold_first_step_keeps_the_start_values_over_the_first_period_then_samples(model, n, t0):
    """With hold_first_step, the outputs after each step of the first period are their start
    values (at h = T: the first step; at h = T / 4 with phase 0: the whole first period, whose
    only sample was the first step), the later periods sample, and without it the run differs (the
    first step samples; a derivator's first sample only seeds it, so that shows a step later).  From t0 = 1.5 s too: the held step is the one from the start time, not
    from t = 0."""
    held, free = _rows(model, n, t0, True), _rows(model, n, t0, False)
    start = held[0]
    np.testing.assert_array_equal(free[0], start)                   # the same start values
    np.testing.assert_array_equal(held[1:n + 1], np.tile(start, (n, 1)))
    assert not np.array_equal(held[-1], start), "the later periods sample"
    assert not np.array_equal(held, free), "without the hold the first step samples"


@pytest.mark.parametrize("model", SAMPLED)
def test_hold_first_step_is_false_unless_set(model):
    """The documented default (fmus/slave/sampling.py: "Boolean, default false"): a slave whose
    hold_first_step is not set samples on its first step, as one set to false."""
    assert slave_class(model)(instance_name="fresh").hold_first_step is False
    _, inputs, outputs = SAMPLED[model]
    unset = new_slave(model)
    for k in range(2):
        for index, (name, (base, amplitude)) in enumerate(inputs.items()):
            setattr(unset, name, input_value(base, amplitude, k, 0, index))
        assert unset.do_step(k * T, T), unset.error
    np.testing.assert_array_equal([getattr(unset, name) for name in outputs], _rows(model, 1, 0.0, False)[2])
