"""A kernel segment's decline by any of its members (fmus/cosim/segments.py): the member that
declined and the rest of the segment's step run in Python, from that member on, whatever its
place in the segment, the first included, so the rows are the Python slaves' rows."""
from __future__ import annotations

from dataclasses import replace

from fmus.cosim.master import _instantiate, stepping_order
from fmus.cosim.segments import Segments
from fmus.cosim.stepper import Stepper
from scenarios.scenes.catalogue import get_scene


def _stepper(system, kernels):
    instances = _instantiate(system, "inprocess", None)
    order = stepping_order(system, {n: i.variables for n, i in instances.items()})
    stepper = Stepper(system, instances, order, kernels=Segments if kernels else None)
    stepper.initialize(0.0)
    return stepper


def _python_class(stepper, name):
    """``name``'s slave made an instance of a subclass of its model: not parcosim's own class,
    so it keeps its Python step and ends the segment before it."""
    slave = stepper.instances[name].slave
    slave.__class__ = type(f"User{type(slave).__name__}", (type(slave),), {})


def test_a_decline_by_the_first_member_of_a_segment_is_taken_in_python():
    # The controller's table covers only x <= 0.02 m: elsewhere its kernel declines the sample.
    # The derivator, stepped before it, is made a user's class: the segment starts at the
    # controller, so its declines come from member 0 of the segment.
    """Catches a decline by the segment's first member (index 0) taken for "nothing declined":
    the controller's sample and the rest of the step skipped (training seed 4213 [19])."""
    system = replace(get_scene("bench_circle_TCx").system, stop_time=1.2)
    system = replace(system, components=tuple(
        replace(c, parameters={**c.parameters, "x_max": 0.02}) if c.name == "ctrl" else c for c in system.components))
    fast, slow = _stepper(system, kernels=True), _stepper(system, kernels=False)
    assert fast.order[:2] == ("deriv", "ctrl")
    _python_class(fast, "deriv")
    _python_class(slow, "deriv")
    declined = 0
    for k in range(system.steps):
        fast.step()
        slow.step()
        assert fast.row() == slow.row(), f"step {k + 1}"
        segment = fast._kernels.segments[0]
        declined += segment._call.stop.member == 0
    assert segment.positions[0] == (fast.order.index("ctrl"), 0)
    assert declined > 10   # the first member did decline, many times
