"""The controller's settings and references are values (seed 4201 [202]): frozen dataclasses.

A settings record is validated when it is used (``BalanceSettings.validate``) and a design
keeps the record it was made for (``BalanceDesign.settings``); ``design_balance``'s default
argument is one shared instance.  A record that could be assigned after the fact would let a
design disagree with the settings it names and let one caller change every later caller's
default, and an eq dataclass that is not frozen is unhashable (it cannot key a cache or a
set).  So each record refuses assignment and equal records hash equal."""
from __future__ import annotations

import dataclasses

import pytest

from controller.balance import BalanceSettings, design_balance, get_route
from controller.strategies import STRATEGY_NAMES, get_strategy
from controller.trajectories import TRAJECTORY_KINDS, get_trajectory


def records():
    """One instance of each of the controller's value records (name, record)."""
    yield "BalanceSettings", BalanceSettings()
    yield "BalanceSettings(yaw=False)", BalanceSettings(T=2e-3, yaw=False)
    for name in ("hold", "forward_turn"):
        yield f"route {name}", get_route(name)
    for name in STRATEGY_NAMES:
        yield f"strategy {name}", get_strategy(name)
    for kind in TRAJECTORY_KINDS:
        yield f"trajectory {kind}", get_trajectory(kind)


@pytest.mark.parametrize("name, record", list(records()), ids=lambda v: v if isinstance(v, str) else "")
def test_each_controller_record_refuses_assignment_and_hashes_as_its_equal_copy(name, record):
    """Assigning any field raises FrozenInstanceError and leaves the value; a field-by-field copy
    is equal to it and hashes the same (where its fields are hashable: numbers, tuples, strings)."""
    for f in dataclasses.fields(record):
        before = getattr(record, f.name)
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(record, f.name, before)
        assert getattr(record, f.name) is before
    copy = dataclasses.replace(record)
    assert copy == record and copy is not record
    if all(isinstance(getattr(record, f.name), (int, float, str, bool, tuple)) for f in dataclasses.fields(record)):
        assert hash(copy) == hash(record)
        assert len({copy, record}) == 1


def test_a_balance_design_keeps_the_settings_it_was_made_for():
    """The design's settings are the very record designed for (frozen: it cannot drift from the
    gains afterwards), and the shared default record is not changed by designing with it."""
    settings = BalanceSettings(T=2e-3, yaw=False)
    design = design_balance(settings)
    assert design.settings is settings
    with pytest.raises(dataclasses.FrozenInstanceError):
        design.settings.T = 1e-3
    assert design_balance().settings == BalanceSettings()
    with pytest.raises(dataclasses.FrozenInstanceError):
        design.K = None
