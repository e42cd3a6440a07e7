"""The GUID a slave takes from its FMU's identity (fmus/slave/identity.py, written into the
resources at build) and what it decides about states (fmus/slave/state_calls.py): a state
carries its FMU's GUID, and an instance of another FMU refuses it by both GUIDs.

In process, with a resources folder made here (the build's file, read back exactly): fast;
tests/fmus/slave/test_fmu_state_data.py does the same through built FMUs.  Also the fields
a state takes of an object (fmus/slave/state.py ``object_fields``): its dict and its slots.
"""
from __future__ import annotations

import hashlib
import json
import struct

import pytest

from fmus.cosim.backends import InProcessInstance
from fmus.slave.base import FmiError
from fmus.slave.identity import IDENTITY_FILE, read_identity
from fmus.slaves.parcosim_trajectory import Trajectory


def _resources(tmp_path, name: str, identity) -> str:
    folder = tmp_path / name
    folder.mkdir()
    (folder / IDENTITY_FILE).write_text(identity if isinstance(identity, str) else json.dumps(identity))
    return str(folder)


def test_the_identity_is_read_from_the_resources_exactly_or_is_empty(tmp_path):
    """Catches the file not read (a folder given), read where there is no folder, or a file
    that is not a JSON object taken as one."""
    identity = {"guid": "{6a1d-ä}", "model": "Trajectory", "built_by": "parcosim", "model_identifier": "Trajectory"}
    assert read_identity(_resources(tmp_path, "own", identity)) == identity
    assert read_identity(None) == read_identity("") == {}
    assert read_identity(str(tmp_path / "missing")) == {}
    assert read_identity(_resources(tmp_path, "list", [1, 2])) == {}
    assert read_identity(_resources(tmp_path, "broken", "{not json")) == {}


def _running(resources) -> Trajectory:
    slave = Trajectory(instance_name="t", resources=resources)
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    for k in range(3):
        slave.do_step(k * 1e-3, 1e-3)
    return slave


def test_a_state_carries_its_fmus_guid_and_only_that_fmu_reads_it(tmp_path):
    """Catches a slave whose GUID is not its identity's, a state that does not carry it, and
    a GUID check inverted or skipped (a state of another FMU read, or this FMU's refused)."""
    own = _resources(tmp_path, "own", {"guid": "{A-1}"})
    other = _resources(tmp_path, "other", {"guid": "{B-2}"})
    source = _running(own)
    assert source.fmu_guid == "{A-1}" and _running(None).fmu_guid == ""
    data = type(source)._fmu_state_to_bytes(source._get_fmu_state())
    same = _running(_resources(tmp_path, "copy", {"guid": "{A-1}"}))
    assert same.deserialize_fmu_state(data).guid == "{A-1}"
    for target, guid in ((_running(other), "{B-2}"), (_running(None), "")):
        with pytest.raises(FmiError, match=rf"^fmi2DeSerializeFMUstate: the state is of the FMU with GUID '\{{A-1\}}', "
                                           rf"this is {guid!r} \(.*\); nothing was read$"):
            target.deserialize_fmu_state(data)


class _Base:
    __slots__ = ("a", "unset")


class _Slotted(_Base):
    __slots__ = ("b", "__weakref__")


class _Both(_Slotted):
    pass      # no __slots__: a __dict__ as well


def test_an_objects_fields_are_its_dict_and_every_set_slot_of_its_classes():
    """Catches slots of a base class missed, an unset slot read (AttributeError), the
    bookkeeping slots taken as fields, or an object with neither dict nor slots not None.
    No model's state has a slotted object today: this is the only test of those lines."""
    from fmus.slave.state import object_fields

    slotted = _Slotted()
    slotted.a, slotted.b = 1.5, [2]
    assert object_fields(slotted) == {"a": 1.5, "b": [2]}
    both = _Both()
    both.a, both.c = "x", 3
    assert object_fields(both) == {"c": 3, "a": "x"}
    assert object_fields(object()) is None
    assert object_fields(_Base()) == {}


#: docs/state.md's header: the layout word is 1, and 2 for these models (their derivator buffer changed).
LAYOUT_2 = ("Derivator", "ClosedLoop", "ControlChain")
IN_PROCESS = ("ActuatedFiveBarPlant", "BalanceController", "CurrentObserver", "DCMotorDrive", "Derivator",
              "FiveBarPlant", "PositionController", "Trajectory", "WheeledPendulum")


@pytest.mark.parametrize("model", IN_PROCESS)
def test_a_serialised_state_has_the_documented_header_word_for_word(model):
    """The bytes of an initialised instance's state, read by docs/state.md's table here (magic, version 1,
    the length of the whole buffer, the model, the GUID ("" in process), 32 bytes of configuration, the
    layout word 1, or 2 for the models whose derivator buffer changed, then the value and a SHA-256 of all
    before it).  Catches a layout version, length or checksum written off the documented table (a state
    of another build then read as this one's)."""
    instance = InProcessInstance(model, "m")
    instance.enter_initialization({}, 0.0)
    instance.exit_initialization()
    slave = instance.slave
    data = type(slave)._fmu_state_to_bytes(slave._get_fmu_state())
    assert data[:8] == b"PCSTATE\0"
    version, length = struct.unpack_from("<IQ", data, 8)
    at = 20
    texts = []
    for _ in range(2):
        (n,) = struct.unpack_from("<H", data, at)
        texts.append(data[at + 2:at + 2 + n].decode())
        at += 2 + n
    (layout,) = struct.unpack_from("<I", data, at + 32)
    assert (version, length, texts) == (1, len(data), [model, ""])
    assert layout == (2 if model in LAYOUT_2 else 1)
    assert data[-32:] == hashlib.sha256(data[:-32]).digest()
