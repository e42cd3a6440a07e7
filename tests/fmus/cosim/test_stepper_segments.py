"""The in-process stepper's kernel segments (fmus.cosim.segments): C-backed slaves stepped by
their compiled I/O steps, one C call per run of consecutive ones, against every slave through
its Python ``do_step`` (tests.support.inprocess.python_slaves)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim.master import _instantiate, simulate, stepping_order
from fmus.cosim.segments import Segments
from fmus.cosim.stepper import Stepper
from scenarios.scenes.catalogue import get_scene
from tests.support.inprocess import python_slaves


def _bench(stop_time=0.3, **changes):
    """bench_circle_TCMDx cut to ``stop_time``; ``changes``: instance -> its new parameters
    (``substeps`` sets the component's sub-steps)."""
    system = get_scene("bench_circle_TCMDx").system
    components = []
    for c in system.components:
        extra = dict(changes.get(c.name, {}))
        substeps = extra.pop("substeps", c.substeps)
        components.append(replace(c, parameters={**c.parameters, **extra}, substeps=substeps))
    return replace(system, components=tuple(components), stop_time=stop_time)


def _both(system):
    fast = simulate(system, mode="inprocess")
    with python_slaves():
        slow = simulate(system, mode="inprocess")
    return fast, slow


def _same_rows(a, b):
    assert a.signals.keys() == b.signals.keys()
    for name in a.signals:
        assert np.array_equal(a[name], b[name], equal_nan=True), name


def _stepper(system, kernels):
    instances = _instantiate(system, "inprocess", None)
    order = stepping_order(system, {n: i.variables for n, i in instances.items()})
    stepper = Stepper(system, instances, order, kernels=Segments if kernels else None)
    stepper.initialize(0.0)
    return stepper


@pytest.mark.parametrize("changes, segments", [
    ({}, 1),
    # the observer samples on the second sub-step: its adapter declines, it steps in Python
    # between two segments
    ({"obs1": {"hold_first_step": True}}, 2),
    # the drives and the plant in 4 sub-steps of the step: one multi-rate group in a segment
    ({"drive1": {"substeps": 4}, "drive2": {"substeps": 4}, "plant": {"substeps": 4}}, 1),
], ids=["one_segment", "python_member_between", "multi_rate"])
def test_segment_rows_are_the_python_slaves_rows(changes, segments):
    """Catches a copy plan, a stepping order, a sub-step time or a Python member between
    segments that makes the kernels' rows differ from the Python slaves' by a bit."""
    system = _bench(**changes)
    fast, slow = _both(system)
    assert fast.error is None and slow.error is None
    _same_rows(fast, slow)
    stepper = _stepper(system, kernels=True)
    stepper.step()
    assert len(stepper._kernels.segments) == segments
    python = [c for c in stepper._kernels.calls if c.step.__name__ != "step" or c.pull is not None]
    assert len(python) == (1 if segments == 2 else 0)


def test_a_sample_the_kernel_declines_is_taken_in_python_and_the_run_goes_on():
    # The controller's table covers only x <= 0.02 m: elsewhere the law's kernel declines and
    # the Python controller takes the sample with the exact model (as in test_compiled).
    """Catches a declined member skipped, stepped twice, or its segment left released."""
    scene = get_scene("bench_circle_TCx")
    system = replace(scene.system, stop_time=1.2)
    system = replace(system, components=tuple(
        replace(c, parameters={**c.parameters, "x_max": 0.02}) if c.name == "ctrl" else c for c in system.components))
    fast, slow = _both(system)
    assert fast.error is None
    _same_rows(fast, slow)


def test_a_state_taken_while_the_kernels_step_goes_back_to_the_same_rows():
    """Catches a state (fmi2GetFMUstate of each slave) taken from slaves the kernels left stale:
    the steps after its restore would differ from the first time."""
    system = _bench()
    stepper = _stepper(system, kernels=True)
    for _ in range(40):
        stepper.step()
    state = stepper.state()

    def rows():
        out = []
        for _ in range(30):
            stepper.step()
            out.append(stepper.row())
        return out
    first = rows()
    stepper.restore(state)
    assert rows() == first
    python = _stepper(system, kernels=False)
    for _ in range(40):
        python.step()
    assert [python.step() or python.row() for _ in range(30)] == first


def test_released_slaves_hold_the_values_the_python_path_gives_them():
    """Catches a release that leaves a slave's attributes or its plant state where the kernels
    took them (a user reading a slave after an in-process run would read stale values)."""
    system = _bench()
    fast, slow = _stepper(system, kernels=True), _stepper(system, kernels=False)
    for _ in range(25):
        fast.step()
        slow.step()
    fast.release()
    assert not fast._kernels.owned
    for name, inst in fast.instances.items():
        other = slow.instances[name].slave
        for variable in inst.variables.values():
            if variable.causality in ("input", "output") and variable.type == "Real":
                assert getattr(inst.slave, variable.name) == getattr(other, variable.name), (name, variable.name)
    assert np.array_equal(fast.instances["plant"].slave.sim.y, slow.instances["plant"].slave.sim.y)
    fast.step()          # taken again by the kernels, from the released values
    slow.step()
    assert fast.row() == slow.row()


def test_the_row_writer_writes_the_rows_and_refuses_a_row_outside_the_array():
    """Catches a C row write to the wrong row or columns, or past the array's end, and a refusal
    that does not say which row of how many (seed 4101's survivor [263], the message dropped) or
    which array the writer needs (a wider, transposed or flat array is refused too)."""
    system = _bench()
    stepper = _stepper(system, kernels=True)
    data = np.full((4, len(system.record)), np.nan)
    record = stepper.recorder(data)
    for k in (1, 2, 3):
        stepper.step()
        record(k)
        assert tuple(data[k]) == stepper.row()
    assert np.isnan(data[0]).all()
    for k in (0, 4, -1):      # row 0 is the initialisation's, written by Python
        with pytest.raises(IndexError, match=f"^row {k} of 4$"):
            record(k)
    columns = len(system.record)
    with pytest.raises(ValueError, match=f"^a row writer needs a C-contiguous float64 array of {columns} columns$"):
        stepper.recorder(np.zeros((4, columns), dtype=np.float32))
    for refused in (np.zeros((4, columns + 1)), np.zeros((columns, 4)).T, np.zeros(4 * columns)):
        with pytest.raises(ValueError, match="^a row writer needs a C-contiguous float64 array of "):
            stepper.recorder(refused)


def test_a_slave_of_another_class_steps_in_python_between_segments():
    # A user's class derived from a parcosim model (here one that counts its Python steps) is
    # not the class its model's adapter knows: it keeps its own Python step.
    """Catches a kernel taking the step of a slave whose class is not parcosim's own of the model
    (a user's override would be skipped)."""
    system = _bench(stop_time=0.05)
    stepper = _stepper(system, kernels=True)
    obs = stepper.instances["obs1"].slave
    base = type(obs)
    steps = []

    class Counted(base):
        def step(self, current_time, step_size):
            steps.append(current_time)
            return base.step(self, current_time, step_size)

    obs.__class__ = Counted
    python = _stepper(system, kernels=False)
    for _ in range(20):
        stepper.step()
        python.step()
        assert stepper.row() == python.row()
    assert len(steps) == 20 and len(stepper._kernels.segments) == 2


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
