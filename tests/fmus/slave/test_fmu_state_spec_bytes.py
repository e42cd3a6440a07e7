"""The FMU state's bytes held to docs/state.md (issue 31; training seed 4361's survivors in
fmus/slave/state.py and state_format.py): the configuration digest computed independently from
its documented recipe, and each str16 text (model, field name, class tag) taking up to
2^16 - 1 bytes and no more."""
from __future__ import annotations

import hashlib
import struct

import pytest

from fmus.slave import state as fmustate
from fmus.slave import state_format as fmt


def _documented_digest(model: str, parameters: dict) -> bytes:
    """docs/state.md "Configuration digest": the model, NUL, then per parameter sorted by name
    the name, NUL, a type letter and the value (B u8, I i64, R f64, S u32 length + UTF-8)."""
    data = model.encode() + b"\0"
    for name in sorted(parameters):
        value = parameters[name]
        data += name.encode() + b"\0"
        if type(value) is bool:
            data += b"B" + bytes([int(value)])
        elif type(value) is int:
            data += b"I" + value.to_bytes(8, "little", signed=True)
        elif type(value) is float:
            data += b"R" + struct.pack("<d", value)
        else:
            text = value.encode()
            data += b"S" + len(text).to_bytes(4, "little") + text
    return hashlib.sha256(data).digest()


@pytest.mark.parametrize("parameters", [
    {"hold_first_step": True}, {"hold_first_step": False},
    {"T": 0.002, "sample_phase": 3, "mode": "fixed", "hold_first_step": True, "n": -1},
    {"preset": "ω-drive", "x": -0.0},
])
def test_the_configuration_digest_is_the_documented_sha256_of_each_parameter_typed(parameters):
    """Catches a type letter or a value's packing dropped or changed (seed 4361's [5]: the
    Boolean's B dropped: a native FMU, which follows the doc, would refuse every state)."""
    assert fmustate.config_digest("Model", parameters) == _documented_digest("Model", parameters)


def _header(model: str) -> fmt.Header:
    return fmt.Header(model=model, guid="{g}", config=bytes(32), layout=1)


@pytest.mark.parametrize("length", [255, 256, 300, (1 << 16) - 1])
def test_a_str16_text_of_up_to_65535_bytes_round_trips(length):
    """Model name, field name and class tag of ``length`` bytes are written and read back
    exactly.  Catches the str16 limit taken as 2^8 (seed 4361's [9]: 256-byte names refused)."""
    text = "m" * length
    value = {"o": fmt.ObjectRecord(tag=text, fields={text: 1.5})}
    header, back = fmt.decode(fmt.encode(_header(text), value))
    assert header.model == text
    assert back["o"].tag == text and back["o"].fields == {text: 1.5}


def test_a_str16_text_of_65536_bytes_is_refused_naming_its_length():
    """One byte past the u16 length: refused, not silently truncated."""
    with pytest.raises(ValueError, match="string of 65536 bytes is too long for the state format"):
        fmt.encode(_header("m" * (1 << 16)), {})


@pytest.mark.parametrize("last", [
    [None] * 40,                                          # 1 byte per item
    {None: None, True: None, False: None},                # 2 bytes per entry
    fmt.ObjectRecord(tag="c", fields={"": None}),         # 3 bytes per field: str16 "" + None
    fmt.ObjectRecord(tag="c", fields={chr(97 + k): None for k in range(20)}),
])
def test_a_container_of_the_smallest_items_that_ends_the_state_round_trips(last):
    """docs/state.md checks each count against the bytes that remain; a container whose items
    take the fewest bytes its kind allows, exactly filling the rest of the state, is read back.
    Catches a count's least bytes per item raised (seed 4361's [10]: fields taken as 6 bytes each
    refused every object ending a state)."""
    value = {"first": [1, 2], "last": last}
    _, back = fmt.decode(fmt.encode(_header("M"), value))
    if isinstance(last, fmt.ObjectRecord):
        assert (back["last"].tag, back["last"].fields) == (last.tag, last.fields)
    else:
        assert back["last"] == last
