"""A split step (a master retrying a refused step) steps every instance, with the split one
in more sub-steps: the same values as a system built with that many sub-steps."""
import numpy as np
import pytest

from fmus.cosim.master import _close, _instantiate, stepping_order
from fmus.cosim.stepper import Stepper
from scenarios.reference import with_parameters
from scenarios.scenes.catalogue import get_scene


def _stepped(system, split=None):
    instances = _instantiate(system, "inprocess", None)
    try:
        stepper = Stepper(system, instances, stepping_order(system, {n: i.variables for n, i in instances.items()}))
        stepper.initialize(0.0)
        for _ in range(3):
            stepper.step(split=split)
        return np.array(stepper.row()), stepper.order
    finally:
        _close(instances)


#: The bench with its drives in 2 sub-steps: splitting the plant or one drive changes how the
#: multi-rate groups form (a group of one rate splits or merges).
SYSTEM = with_parameters(with_parameters(get_scene("bench_circle_TCMDq").system, "drive1", component_substeps=2),
                         "drive2", component_substeps=2)


@pytest.mark.parametrize("name", ["plant", "drive1", "drive2"])
def test_split_step_equals_a_system_built_with_the_split_substeps(name):
    """Catches the retry's split of one instance's step giving other rows than a system built with that
    many sub-steps (offsets or inputs held wrongly)."""
    own = SYSTEM.component(name).substeps
    split, order = _stepped(SYSTEM, {name: 2})
    built, _ = _stepped(with_parameters(SYSTEM, name, component_substeps=2 * own))
    assert np.array_equal(split, built), (name, order)
