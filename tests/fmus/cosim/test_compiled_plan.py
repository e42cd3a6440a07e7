"""The plan of a compiled run (``Result.extra["plan"]``, fmus/cosim/compiled.py): one line per
member, ``# name (model): kernel``, naming every instance of the system by its own name and
model, once, with the kernel of that model's adapter."""
from __future__ import annotations

from dataclasses import replace

import pytest

from fmus.cosim import compiled
from fmus.cosim.master import simulate
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant

SYSTEMS = {
    "bench_circle_PDq": lambda: get_scene("bench_circle_PDq").system,
    "pendulum_balance": lambda: get_scene("pendulum_balance").system,
    # the drives inside the plant (ActuatedFiveBarPlant), in 2 sub-steps of the step
    "drives_in_plant": lambda: drives_in_plant(get_scene("bench_circle_TCMDx"), substeps=2).system,
    # the drives and the plant in 4 sub-steps of the step (one multi-rate group)
    "multi_rate": lambda: _in_substeps(get_scene("bench_circle_TCMDx").system, ("drive1", "drive2", "plant"), 4),
}


def _in_substeps(system, names, n):
    return replace(system, components=tuple(replace(c, substeps=n) if c.name in names else c
                                            for c in system.components))


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_the_plan_names_every_member_by_its_instance_name_model_and_kernel(name):
    """Each component of the scene has exactly one plan line ``# <instance> (<model>): <kernel>``
    and the plan has no other line: an adapter built with its arguments mixed up (the slave
    object as its name, training seed 4213 [4], the pendulum's controller) or a member listed
    twice or not at all shows here."""
    system = SYSTEMS[name]()
    result = simulate(replace(system, stop_time=0.01), mode="compiled")
    assert result.error is None and result.mode == "compiled"
    lines = result.extra["plan"].split("\n")
    expected = {f"# {c.name} ({c.model}): {compiled.ADAPTERS[c.model].kernel}" for c in system.components}
    assert len(lines) == len(system.components)
    assert {line.split(", ")[0] for line in lines} == expected
    # a member in sub-steps says how many
    for c in system.components:
        line = next(line for line in lines if line.startswith(f"# {c.name} ("))
        assert line.endswith(f", {c.substeps} sub-steps") == (c.substeps > 1), line
