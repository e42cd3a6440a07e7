"""What a system FMU's step spends before its components step (fmus/systemfmu/slave_base.py
``step``): its communication steps times its components' inner doSteps, at
:data:`fmus.slave.budget.INNER_STEP` each, counted here from the system itself (each component's
``substeps``; a ControlChain's model of the plant steps once more, its correction) and read as what
the call's budget has left when the components start (issue 31: an independent count; the inner
steps' factor dropped from the charge passed every test, the refusals being all or nothing)."""
from __future__ import annotations

from dataclasses import replace

import pytest

from fmus.slave import budget
from scenarios.scenes.catalogue import get_scene
from tests.fmus.slave.test_call_limits import system_slave


def _multirate(system):
    """The drives and the plant at 4 sub-steps a communication step (17 inner doSteps)."""
    fast = ("drive1", "drive2", "plant")
    return replace(system, components=tuple(replace(c, substeps=4) if c.name in fast else c
                                            for c in system.components))


def _left_when_advancing(slave, t, h):
    """The budget left when ``slave``'s components start the step from ``t`` over ``h``."""
    seen = []
    advance = slave.advance

    def recorded(current_time, step_size):
        seen.append(budget.active().left)
        return advance(current_time, step_size)

    slave.advance = recorded
    assert slave.do_step(t, h), slave.error
    return seen[0]


@pytest.mark.parametrize("steps", [1, 3])
def test_a_closed_loop_charges_its_steps_times_its_inner_doSteps_first(steps, tmp_path):
    """Catches the charge without the inner steps' count (or without the communication steps)."""
    system = _multirate(get_scene("bench_circle_TCMDx").system)
    inner = sum(c.substeps for c in system.components)
    assert inner == 17
    slave = system_slave(tmp_path, "loop", system)
    left = _left_when_advancing(slave, 0.0, steps * system.step)
    assert left == pytest.approx(budget.CALL_CPU_SECONDS - steps * inner * budget.INNER_STEP, rel=1e-12)


def test_a_control_chain_charges_its_components_and_the_correction_first(tmp_path):
    """Catches the chain's correction (one more step of its model of the plant) left out."""
    from scenarios.packaging.chain import package_scene

    chain = package_scene(get_scene("bench_circle_TCMDx")).chain
    slave = system_slave(tmp_path, "chain", chain)
    inner = sum(c.substeps for c in chain.components) + 1
    left = _left_when_advancing(slave, 0.0, chain.step)
    assert left == pytest.approx(budget.CALL_CPU_SECONDS - inner * budget.INNER_STEP, rel=1e-12)
