"""The state layout the system FMUs read (docs/contract.md: ``Derivator``, ``ClosedLoop`` and
``ControlChain`` write state layout 2 and refuse a layout-1 state, "state layout 1; Derivator
reads layout 2; nothing was read"); the other models read layout 1 and refuse 2."""
from __future__ import annotations

import pytest

from fmus.slave import state_format as sf
from fmus.slave.base import FmiError
from fmus.slaves.parcosim_closedloop import ClosedLoop
from fmus.slaves.parcosim_controlchain import ControlChain
from fmus.slaves.parcosim_derivator import Derivator
from fmus.slaves.parcosim_trajectory import Trajectory

READS = [(ClosedLoop, 2), (ControlChain, 2), (Derivator, 2), (Trajectory, 1)]


def _bytes(model: str, layout: int) -> bytes:
    return sf.encode(sf.Header(model, "", bytes(32), layout), {"x": 1.0})


@pytest.mark.parametrize("cls, layout", READS)
def test_a_state_of_the_documented_layout_is_read_and_another_refused_naming_both(cls, layout):
    decoded = cls._fmu_state_from_bytes(_bytes(cls.__name__, layout))
    assert decoded.header.layout == layout
    other = 3 - layout
    with pytest.raises(FmiError) as refused:
        cls._fmu_state_from_bytes(_bytes(cls.__name__, other))
    assert str(refused.value) == (f"fmi2DeSerializeFMUstate: state layout {other}; {cls.__name__} reads layout "
                                  f"{layout}; nothing was read")
