"""A system FMU's work limit holds for a single communication step too (fmus/systemfmu/
slave_base.py ``check_step_size``; issue 31, training sweep s44: compare mutants at
slave_base.py:69, ``steps < 1`` and ``steps > 1``).

One step h is the least a step size can be (0 steps is the core's refusal, 2 or more a chain's):
its inner work is charged as any other, so with the work limit below one step's work, a step
of exactly h is refused before it is taken, naming the limit, by a ControlChain (which takes
only h) and by a ClosedLoop (which takes whole multiples) alike; at 1.5 steps' work (in a new
instance) it is taken.
"""
from __future__ import annotations

import pytest

from fmus.slave import budget
from tests.fmus.systemfmu.test_embedded_chain import _initialised


@pytest.mark.parametrize("model", ["ControlChain", "ClosedLoop"])
def test_one_step_over_the_work_limit_is_refused_before_it_is_taken_and_one_within_it_is_taken(monkeypatch, model):
    slave = _initialised(model)
    h = slave.system.step
    count, seconds = slave.core.work_per_step()
    assert count > 0
    monkeypatch.setattr(budget, "CALL_CPU_SECONDS", 0.5 * seconds)
    time_before = slave.core.stepper.time
    assert not slave.do_step(0.0, h)
    assert slave.core.stepper.time == time_before
    assert f"step size h = {h!r} s at t = 0.0 s needs {count:.6g} inner steps of {type(slave).__name__}'s system" \
        in slave.error, slave.error
    fresh = _initialised(model)       # a refused step ends the instance's run: a new one
    monkeypatch.setattr(budget, "CALL_CPU_SECONDS", 1.5 * seconds)
    assert fresh.do_step(0.0, h), fresh.error
