"""``fmus.native.state_bytes`` on a state forged here field by field from docs/native.md's
layout table ("FMU state"), with counts of every kind non-zero and of different sizes, so each
field's offset is read back exactly: identifier, GUID, counts, data words, the model data's
offset and every length field's offset and format; ``data_words`` and ``with_data_word`` (the
checksum remade over every byte before it).  The checksum is pcn_state.c's 64-bit FNV-1a, computed
here on its own and held against FNV's published test vectors.  No FMU is built."""
from __future__ import annotations

import struct

import numpy as np
import pytest

from fmus.native.state_bytes import MAGIC, data_words, fnv1a, layout, with_data_word

BASIS, PRIME = 14695981039346656037, 1099511628211   # FNV-1a 64's offset basis; its prime 2**40 + 2**8 + 0xb3


def _fnv(data: bytes) -> int:
    h = BASIS
    for b in data:
        h ^= b
        h = h * PRIME % 2 ** 64
    return h


def _state(identifier="Drive", guid="{g-1}", reals=(1.5, -2.0, 3.25), integers=(7, -9), booleans=(1, 0, 1, 1),
           strings=("", "refusal text"), data=(0.5, 1e-300, -4.0)):
    """A state laid out as the table says (host byte order), and where its parts are."""
    out = bytearray(MAGIC) + struct.pack("=I", 3) + struct.pack("=Q", 0)
    where = {}
    for name, text in (("identifier", identifier), ("guid", guid)):
        where[name] = len(out)
        out += struct.pack("=H", len(text.encode())) + text.encode()
    where["counts"] = len(out)
    out += struct.pack("=4I", len(reals), len(integers), len(booleans), len(strings))
    where["words"] = len(out)
    out += struct.pack("=Q", len(data))
    out += bytes(8) + struct.pack("=4d", 0.0, 2e-3, 1e-3, 0.0)            # flags, four times
    out += struct.pack(f"={len(reals)}d", *reals) + struct.pack(f"={len(integers)}i", *integers)
    out += bytes(booleans)
    where["strings"] = []
    for text in strings:
        where["strings"].append(len(out))
        out += struct.pack("=I", len(text.encode())) + text.encode()
    where["data"] = len(out)
    out += struct.pack(f"={len(data)}d", *data)
    struct.pack_into("=Q", out, 12, len(out) + 8)
    out += struct.pack("=Q", _fnv(bytes(out)))
    return bytes(out), where


def test_the_checksum_is_fnv1a_over_every_byte_with_fnvs_published_basis():
    """Catches the xor and the multiply swapped (FNV-1 for FNV-1a), another prime or basis (format
    version 2 started a digit short of the basis), and no 64-bit wrap.  The three vectors are FNV's
    published FNV-1a 64 test values, so an outside tool checking a state with a stock FNV-1a agrees."""
    for data in (b"", b"a", b"foobar", bytes(range(256)) * 3):
        assert fnv1a(data) == _fnv(data)
    assert fnv1a(b"") == BASIS and fnv1a(b"a") == ((BASIS ^ 0x61) * PRIME) % 2 ** 64
    assert fnv1a(b"ab") != fnv1a(b"ba")
    assert (fnv1a(b""), fnv1a(b"a"), fnv1a(b"foobar")) == (0xCBF29CE484222325, 0xAF63DC4C8601EC8C, 0x85944171F73967E8)


def test_the_layout_reads_each_field_at_its_place():
    state, where = _state()
    found = layout(state)
    assert (found["identifier"], found["guid"]) == ("Drive", "{g-1}")
    assert found["counts"] == (3, 2, 4, 2) and found["data_words"] == 3
    assert found["data_offset"] == where["data"]
    assert found["sizes"] == [(12, "=Q"), (where["identifier"], "=H"), (where["guid"], "=H"),
                              *[(where["counts"] + 4 * k, "=I") for k in range(4)], (where["words"], "=Q"),
                              *[(at, "=I") for at in where["strings"]]]


@pytest.mark.parametrize("kind", ["no strings", "no values", "non-ascii names"])
def test_the_layout_follows_the_counts_and_byte_lengths(kind):
    """Catches a field's offset that holds only for the counts of one state, and a name's
    length read in characters, not bytes."""
    options = {"no strings": dict(strings=()), "no values": dict(reals=(), integers=(), booleans=(), strings=()),
               "non-ascii names": dict(identifier="Dréhmoment", guid="{ü}")}[kind]
    state, where = _state(**options)
    found = layout(state)
    assert found["data_offset"] == where["data"]
    assert len(found["sizes"]) == 8 + len(where["strings"])
    if kind == "non-ascii names":
        assert (found["identifier"], found["guid"]) == ("Dréhmoment", "{ü}")


def test_data_words_are_the_model_data_and_a_word_set_keeps_the_checksum_right():
    state, where = _state()
    np.testing.assert_array_equal(data_words(state), [0.5, 1e-300, -4.0])
    forged = with_data_word(state, 1, -7.5)
    assert len(forged) == len(state)
    np.testing.assert_array_equal(data_words(forged), [0.5, -7.5, -4.0])
    assert forged[:where["data"]] == state[:where["data"]]          # nothing before the data changed
    assert struct.unpack_from("=Q", forged, len(forged) - 8)[0] == _fnv(forged[:-8])
    copy = data_words(state)
    copy[0] = 99.0
    assert data_words(state)[0] == 0.5                              # a copy, not a view of the bytes


def test_bytes_that_are_not_a_native_state_are_refused():
    state, _ = _state()
    with pytest.raises(ValueError, match=r"^not a native FMU state$"):
        layout(b"PCSTATE\x00" + state[8:])
