"""Read a native FMU's serialised state (the bytes of ``fmi2SerializeFMUstate``; layout in
``fmus/native/pcn_state.c`` and docs/native.md): for inspection and for the tests that forge
states.  Host byte order, as the C writes it."""
from __future__ import annotations

import struct

import numpy as np

MAGIC = b"PCNSTATE"
FLAGS = 8


def fnv1a(data: bytes) -> int:
    """The state's checksum: 64-bit FNV-1a."""
    h = 0xCBF29CE484222325   # the FNV-1a 64 offset basis
    for b in data:
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def layout(data: bytes) -> dict:
    """Where the fields are: identifier, guid, counts (Real, Integer, Boolean, String),
    data_words, ``data_offset`` (the model data's first byte) and ``sizes`` (offset and
    struct format of every length or count field: what a forged state would lie about)."""
    if data[:8] != MAGIC:
        raise ValueError("not a native FMU state")
    at = 8 + 4 + 8
    fields, sizes = {}, [(12, "=Q")]
    for name in ("identifier", "guid"):
        (n,) = struct.unpack_from("=H", data, at)
        sizes.append((at, "=H"))
        fields[name] = data[at + 2:at + 2 + n].decode()
        at += 2 + n
    counts = struct.unpack_from("=4I", data, at)
    (words,) = struct.unpack_from("=Q", data, at + 16)
    sizes += [(at + 4 * k, "=I") for k in range(4)] + [(at + 16, "=Q")]
    at += 16 + 8 + FLAGS + 4 * 8 + 8 * counts[0] + 4 * counts[1] + counts[2]
    for _ in range(counts[3]):
        (n,) = struct.unpack_from("=I", data, at)
        sizes.append((at, "=I"))
        at += 4 + n
    fields.update(counts=counts, data_words=words, data_offset=at, sizes=sizes)
    return fields


def data_words(data: bytes) -> np.ndarray:
    """The model data of a state (a copy), as doubles."""
    where = layout(data)
    return np.frombuffer(data, dtype=np.float64, count=where["data_words"], offset=where["data_offset"]).copy()


def with_data_word(data: bytes, index: int, value: float) -> bytes:
    """The state with model data word ``index`` set to ``value`` and the checksum recomputed."""
    where = layout(data)
    out = bytearray(data)
    struct.pack_into("=d", out, where["data_offset"] + 8 * index, value)
    struct.pack_into("=Q", out, len(out) - 8, fnv1a(bytes(out[:-8])))
    return bytes(out)
