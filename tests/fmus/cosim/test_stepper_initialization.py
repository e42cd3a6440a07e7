"""The order in which a stepper's instances leave initialisation mode
(:meth:`fmus.cosim.stepper.Stepper.initialization_order`) and the clock :meth:`initialize` sets:
every source before its readers where the connections allow it, whatever the stepping order;
in a loop, the first in the stepping order first; a connection of an instance to itself
orders nothing; with no start time given, the run starts at t = 0."""
from __future__ import annotations

import pytest

from fmus.cosim.master import _close, _instantiate
from fmus.cosim.stepper import Stepper
from fmus.cosim.system import Component, Connection, System

H = 1e-3


def _order(connections, order, start=None):
    """(names in initialisation order, the stepper's start time and time after initialize)."""
    system = System((Component("drive", "DCMotorDrive", {"mode": "voltage"}), Component("obs", "CurrentObserver")),
                    tuple(Connection(s, t) for s, t in connections), ("drive.i",), stop_time=10 * H, step=H)
    instances = _instantiate(system, "inprocess", None)
    try:
        stepper = Stepper(system, instances, order, jacobi=True)     # Jacobi: any stepping order
        names = [e.name for e in stepper.initialization_order()]
        if start is None:
            stepper.initialize()
        else:
            stepper.initialize(start)
        return names, stepper.start_time, stepper.time
    finally:
        _close(instances)


@pytest.mark.parametrize("order", [("obs", "drive"), ("drive", "obs")])
def test_a_source_leaves_initialisation_before_its_reader_in_either_stepping_order(order):
    """Catches the connections between instances left out of the order (the stepping order
    used as is: the observer would read the drive's voltage before the drive computed it)."""
    names, _, _ = _order([("drive.v", "obs.v")], order)
    assert names == ["drive", "obs"]


@pytest.mark.parametrize("order", [("obs", "drive"), ("drive", "obs")])
def test_in_a_loop_the_first_in_the_stepping_order_leaves_first(order):
    names, _, _ = _order([("drive.v", "obs.v"), ("obs.i_hat", "drive.i_hat")], order)
    assert names == list(order)


def test_a_connection_of_an_instance_to_itself_orders_nothing():
    """The drive's own current fed back to its estimate is no loop with the observer: the drive,
    source of the observer, still goes first though the observer steps first."""
    names, _, _ = _order([("drive.i", "drive.i_hat"), ("drive.v", "obs.v")], ("obs", "drive"))
    assert names == ["drive", "obs"]


def test_initialize_without_a_start_time_starts_the_clock_at_zero():
    assert _order([], ("drive", "obs"))[1:] == (0.0, 0.0)
    assert _order([], ("drive", "obs"), start=0.25)[1:] == (0.25, 0.25)
