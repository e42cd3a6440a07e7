"""What a system FMU counts as its work before a step (``fmus.systemfmu.cores``): the inner
doSteps of one communication step are its components' sub-steps, plus, in a ControlChain, the
corrected step of its model of the plant; the count the step spends (``inner_steps``) and the
count the step size is checked against (``work_per_step``) are the same, counted here again
from the system's components (issue 31: a miscount passed every test with one sub-step each)."""
from __future__ import annotations

from dataclasses import replace

import pytest

from fmus.slave import budget
from fmus.systemfmu.cores import ChainCore, LoopCore
from scenarios.packaging.chain import package_scene
from scenarios.scenes.catalogue import get_scene

SUBSTEPS = {"drive1": 3, "drive2": 2, "deriv": 4}


def _with_substeps(system):
    return replace(system, components=tuple(replace(c, substeps=SUBSTEPS.get(c.name, 1)) for c in system.components))


@pytest.fixture(scope="module")
def systems():
    scene = get_scene("bench_circle_TCMDx")
    return _with_substeps(scene.system), _with_substeps(package_scene(scene).chain)


def test_a_loops_work_is_its_components_substeps(systems):
    """Catches a component counted once whatever its sub-steps, or the two counts apart."""
    system, _ = systems
    core = LoopCore(system)
    core.initialize()
    expected = sum(c.substeps for c in system.components)
    assert expected == len(system.components) + sum(k - 1 for k in SUBSTEPS.values())
    count, seconds = core.work_per_step()
    assert core.inner_steps() == count == expected and seconds >= expected * budget.INNER_STEP


def test_a_chains_work_adds_the_corrected_step_of_its_plant_model(systems):
    """Catches the model's corrected step not counted (or taken away) in either count."""
    _, chain = systems
    core = ChainCore(chain)
    core.initialize()
    plant = next(c for c in chain.components if c.name == "plant")
    expected = sum(c.substeps for c in chain.components) + 1
    count, seconds = core.work_per_step()
    assert core.inner_steps() == count == expected
    assert seconds >= expected * budget.INNER_STEP and plant.substeps >= 1
