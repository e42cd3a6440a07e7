"""The state format's bytes against the table of fmus/slave/state_format.py (docs/state.md),
written here a second time from the table, and its limits at their edge.

The writer and the reader of :mod:`fmus.slave.state_format` are held to an independent
encoder (:func:`_bytes_of`, one branch per tag of the table), every value read back exactly;
each limit (nesting depth, value count, array dimensions, counts against the bytes left) is
met at its edge (accepted) and one past it (refused, the message naming the limit and the
offset where the reader was).
"""
from __future__ import annotations

import hashlib
import struct

import numpy as np
import pytest

from fmus.slave import state_format as sf

HEADER = sf.Header("Model", "{guid}", bytes(range(32)), 7)


def _s(text: str, size: str) -> bytes:
    data = text.encode()
    return struct.pack(size, len(data)) + data


def _bytes_of(v) -> bytes:
    """The table of the module's docstring, one row a branch."""
    if v is None:
        return b"N"
    if v is True or v is False:
        return b"T" if v else b"F"
    if type(v) is int:
        return b"i" + struct.pack("<q", v)
    if type(v) is float:
        return b"f" + struct.pack("<d", v)
    if type(v) is complex:
        return b"c" + struct.pack("<d", v.real) + struct.pack("<d", v.imag)
    if type(v) is str:
        return b"s" + struct.pack("<I", len(v.encode())) + v.encode()
    if type(v) is bytes:
        return b"y" + struct.pack("<I", len(v)) + v
    if isinstance(v, np.ndarray):
        raw = np.ascontiguousarray(v).tobytes()
        return (b"a" + _s(v.dtype.str, "<H") + struct.pack("<B", v.ndim)
                + b"".join(struct.pack("<Q", n) for n in v.shape) + struct.pack("<Q", len(raw)) + raw)
    if isinstance(v, np.generic):
        return b"g" + _s(v.dtype.str, "<B") + struct.pack("<B", v.itemsize) + v.tobytes()
    if type(v) in (tuple, list):
        return (b"t" if type(v) is tuple else b"l") + struct.pack("<I", len(v)) + b"".join(map(_bytes_of, v))
    if type(v) is dict:
        return b"d" + struct.pack("<I", len(v)) + b"".join(_bytes_of(k) + _bytes_of(x) for k, x in v.items())
    if isinstance(v, sf.ObjectRecord):
        return (b"o" + _s(v.tag, "<H") + struct.pack("<I", len(v.fields))
                + b"".join(_s(k, "<H") + _bytes_of(x) for k, x in v.fields.items()))
    if isinstance(v, sf.Opaque):
        return b"x" + _s(v.tag, "<H")
    if isinstance(v, sf.Ref):
        return b"r" + struct.pack("<I", v.index)
    raise AssertionError(f"no row of the table for {v!r}")


def _framed(value_bytes: bytes, header: sf.Header = HEADER) -> bytes:
    """The layout of the docstring around ``value_bytes``: magic, version, length, model,
    guid, config, layout, value, SHA-256."""
    body = (_s(header.model, "<H") + _s(header.guid, "<H") + header.config + struct.pack("<I", header.layout)
            + value_bytes)
    head = sf.MAGIC + struct.pack("<I", sf.FORMAT_VERSION) + struct.pack("<Q", 8 + 12 + len(body) + 32)
    return head + body + hashlib.sha256(head + body).digest()


def _value_offset(header: sf.Header = HEADER) -> int:
    return 8 + 12 + 2 + len(header.model.encode()) + 2 + len(header.guid.encode()) + 32 + 4


EVERY_TAG = {
    "none": None, "yes": True, "no": False, "int": -(2 ** 40) + 3, "float": -0.1, "complex": 1.5 - 2.25j,
    "str": "Wärme π", "bytes": b"\x00\xffab", "tuple": (1, (2.0, "x")), "list": [[], [None]],
    "f8": np.array([[1.0, -2.5, 3.25]]), "i4": np.arange(4, dtype="<i4"), "u1": np.array([7, 255], dtype="u1"),
    "bool": np.array([True, False]), "c16": np.array([1j, 2.0]),
    "scalar": np.float32(2.5), "iscalar": np.int16(-3),
    "object": sf.ObjectRecord("plant.X", {"a": 1.0, "b": [2, 3]}), "code": sf.Opaque("function:math.sin"),
    2: "an int key", (1, "k"): "a tuple key",
}


def _equal(a, b) -> bool:
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    if isinstance(a, np.generic):
        return type(a) is type(b) and a.tobytes() == b.tobytes()
    if type(a) in (tuple, list):
        return type(a) is type(b) and len(a) == len(b) and all(map(_equal, a, b))
    if type(a) is dict:
        return type(b) is dict and list(a) == list(b) and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, sf.ObjectRecord):
        return isinstance(b, sf.ObjectRecord) and a.tag == b.tag and _equal(a.fields, b.fields)
    return type(a) is type(b) and a == b


def test_every_tag_is_written_as_the_table_says_and_read_back_exactly():
    """Catches a writer or reader off the documented layout in any row (a tag, a length's
    width, a field's order, a count, the header's fields or the length word) and a value not
    read back as it was written (type, dtype, shape, key order)."""
    data = sf.encode(HEADER, EVERY_TAG)
    assert data == _framed(_bytes_of(EVERY_TAG))
    header, value = sf.decode(data)
    assert header == HEADER
    assert _equal(EVERY_TAG, value)


def test_references_name_lists_dicts_objects_and_arrays_in_the_order_written():
    """A reference is the index of an earlier list, dict, object or array, counted in the
    order they are written (tuples, scalars and opaque tags are not counted).  Catches a
    writer or reader that numbers another kind, or skips one, and a reader that lets a
    reference name a value not met yet."""
    shared = [1.0]
    arr = np.zeros(2)
    tree = {"t": (sf.Opaque("x"), np.float64(1.0)), "a": arr, "o": sf.ObjectRecord("m.C", {"l": shared}),
            "again": sf.SharedRef(shared), "arr": sf.SharedRef(arr)}
    # written: dict 0, array 1, object 2, list 3
    expected = dict(tree, again=sf.Ref(3), arr=sf.Ref(1))
    data = sf.encode(HEADER, tree)
    assert data == _framed(_bytes_of(expected))
    assert _equal(expected, sf.decode(data)[1])
    with pytest.raises(ValueError, match="a reference to a value not written before it"):
        sf.encode(HEADER, [sf.SharedRef([2.0])])
    # a list, a dict and an array met (3 values): index 3 names one not met yet
    bad = b"l" + struct.pack("<I", 2) + _bytes_of({"a": arr}) + b"r" + struct.pack("<I", 3)
    offset = _value_offset() + len(bad)
    with pytest.raises(sf.StateFormatError, match=rf"^a reference to value 3 of 3 met so far at offset {offset}$"):
        sf.decode(_framed(bad))


def _nested(kind: str, levels: int):
    """A value ``levels`` containers deep (the innermost holding 0.0) of one kind."""
    v = 0.0
    for _ in range(levels):
        v = {"tuple": lambda x: (x,), "list": lambda x: [x], "dict": lambda x: {"k": x},
             "object": lambda x: sf.ObjectRecord("m.C", {"f": x})}[kind](v)
    return v


@pytest.mark.parametrize("kind", ["tuple", "list", "dict", "object"])
def test_nesting_is_allowed_to_max_depth_and_refused_one_level_deeper_by_writer_and_reader(kind):
    """The top value is at depth 0; a value at depth MAX_DEPTH is read, one at MAX_DEPTH + 1
    refused (the writer by ValueError, the reader by name and offset).  Catches a depth not
    passed on (or decreased) into any kind of container, and a limit off by one."""
    deepest = _nested(kind, sf.MAX_DEPTH)
    assert _equal(deepest, sf.decode(sf.encode(HEADER, deepest))[1])
    deeper = _nested(kind, sf.MAX_DEPTH + 1)
    with pytest.raises(ValueError, match=f"^the state is nested deeper than {sf.MAX_DEPTH} levels$"):
        sf.encode(HEADER, deeper)
    raw = _bytes_of(deeper)
    # the first value one level too deep: the innermost 0.0 (9 bytes, last), or its dict's key "k" (6 bytes)
    at = _value_offset() + len(raw) - 9 - (6 if kind == "dict" else 0)
    with pytest.raises(sf.StateFormatError, match=f"^values nested deeper than {sf.MAX_DEPTH} levels at offset {at}$"):
        sf.decode(_framed(raw))


def test_a_dict_key_is_one_level_deeper_than_its_dict():
    """Catches a key read or written at its dict's depth."""
    key = 0.0
    for _ in range(sf.MAX_DEPTH - 1):
        key = (key,)
    assert _equal({key: 1}, sf.decode(sf.encode(HEADER, {key: 1}))[1])
    with pytest.raises(ValueError, match="nested deeper"):
        sf.encode(HEADER, {(key,): 1})
    with pytest.raises(sf.StateFormatError, match="values nested deeper"):
        sf.decode(_framed(_bytes_of({(key,): 1})))


def test_the_value_count_is_limited_and_every_value_counts(monkeypatch):
    """Catches a reader that does not count a container, or its items, against MAX_VALUES,
    or is off by one at the limit."""
    monkeypatch.setattr(sf, "MAX_VALUES", 6)
    ok = {"a": [None, 1]}            # dict, "a", list, None, 1: 5 values
    assert sf.decode(sf.encode(HEADER, ok))[1] == ok
    assert sf.decode(sf.encode(HEADER, {"a": [None, 1, 2]}))[1] == {"a": [None, 1, 2]}   # 6
    raw = _bytes_of({"a": [None, 1, 2, 3]})
    at = _value_offset() + len(raw) - 9
    with pytest.raises(sf.StateFormatError, match=f"^more than 6 values at offset {at}$"):
        sf.decode(_framed(raw))


@pytest.mark.parametrize("tag, items, n, what", [(b"l", b"NTFN", 4, "tuple/list count"),
                                                 (b"t", b"NTFN", 4, "tuple/list count"),
                                                 (b"d", b"NNTNFN", 3, "dict count"),     # 2 bytes a pair
                                                 (b"s", b"abcd", 4, "str length"), (b"y", b"abcd", 4, "bytes length")])
def test_a_count_is_checked_against_the_bytes_left_before_anything_is_read(tag, items, n, what):
    """A count whose items (each at least one byte, a dict's pair two) cannot fit the bytes
    left is refused by name; the count that just fits is read.  Catches a count check with the
    wrong least size, or none."""
    assert len(sf.decode(_framed(tag + struct.pack("<I", n) + items))[1]) == n
    at = _value_offset() + 5
    with pytest.raises(sf.StateFormatError,
                       match=f"^{what} {n + 1} is more than the bytes left can hold at offset {at}$"):
        sf.decode(_framed(tag + struct.pack("<I", n + 1) + items))


def test_an_object_needs_three_bytes_a_field():
    """Catches an object's field count checked against too few bytes a field."""
    fields = b"".join(_s(k, "<H") + b"N" for k in "ab")     # 2 fields, 6 bytes
    ok = b"o" + _s("m.C", "<H") + struct.pack("<I", 2) + fields
    assert sf.decode(_framed(ok))[1] == sf.ObjectRecord("m.C", {"a": None, "b": None})
    bad = b"o" + _s("m.C", "<H") + struct.pack("<I", 3) + fields
    at = _value_offset() + 1 + 2 + 3 + 4
    with pytest.raises(sf.StateFormatError, match=f"^field count 3 is more than the bytes left can hold at offset {at}$"):
        sf.decode(_framed(bad))
    twice = b"o" + _s("m.C", "<H") + struct.pack("<I", 2) + (_s("a", "<H") + b"N") * 2
    with pytest.raises(sf.StateFormatError, match=r"^field 'a' of m.C given twice at offset "):
        sf.decode(_framed(twice))


def test_arrays_are_refused_by_dimensions_size_and_kept_as_bytes_when_their_dtype_is_not_plain():
    """Catches the MAX_NDIM limit off by one, a shape that does not match its bytes read
    anyway, and a record dtype read as if it were plain."""
    deepest = np.zeros((1,) * sf.MAX_NDIM)
    assert _equal(deepest, sf.decode(sf.encode(HEADER, deepest))[1])
    raw = _bytes_of(np.zeros((1,) * (sf.MAX_NDIM + 1)))
    at = _value_offset() + 1 + 5 + 1
    with pytest.raises(sf.StateFormatError, match=f"^an array of {sf.MAX_NDIM + 1} dimensions "
                                                  rf"\(at most {sf.MAX_NDIM}\) at offset {at}$"):
        sf.decode(_framed(raw))
    lying = b"a" + _s("<f8", "<H") + struct.pack("<B", 1) + struct.pack("<Q", 3) + struct.pack("<Q", 16) + bytes(16)
    with pytest.raises(sf.StateFormatError, match=r"^an array of shape \(3,\) and dtype <f8 in 16 bytes at offset "):
        sf.decode(_framed(lying))
    record = np.zeros(2, dtype=[("a", "<f8"), ("b", "<i4")])
    read = sf.decode(sf.encode(HEADER, record))[1]
    assert read == sf.ArrayBytes(sf.dtype_key(record.dtype), (2,), record.tobytes())
    assert sf.dtype_key(record.dtype) == repr(record.dtype.descr)


def test_scalars_are_refused_by_dtype_and_size():
    """Catches a numpy scalar read with an unlisted dtype or a size other than its dtype's."""
    unknown = b"g" + _s("<m8[s]", "<B") + struct.pack("<B", 8) + bytes(8)
    with pytest.raises(sf.StateFormatError, match=r"^a numpy scalar of dtype '<m8\[s\]' \(not one of "):
        sf.decode(_framed(unknown))
    short = b"g" + _s("<f8", "<B") + struct.pack("<B", 4) + bytes(4)
    with pytest.raises(sf.StateFormatError, match="^a <f8 scalar of 4 bytes at offset "):
        sf.decode(_framed(short))


def test_values_the_format_has_no_row_for_are_refused():
    """Catches a reader that skips an unknown tag, an unhashable key or bytes left over, and a
    writer that writes what it cannot read back."""
    at = _value_offset() + 1
    with pytest.raises(sf.StateFormatError, match=f"^unknown value tag b'Q' at offset {at}$"):
        sf.decode(_framed(b"Q"))
    with pytest.raises(sf.StateFormatError, match="^a dict key of type list at offset "):
        sf.decode(_framed(b"d" + struct.pack("<I", 1) + _bytes_of([]) + b"N"))
    with pytest.raises(sf.StateFormatError, match=f"^2 bytes left over after the state's value at offset {at}$"):
        sf.decode(_framed(b"NNN"))
    with pytest.raises(TypeError, match="^a set cannot be written into a state$"):
        sf.encode(HEADER, {1, 2})
    with pytest.raises(ValueError, match="^the configuration digest has 31 bytes, not 32$"):
        sf.encode(sf.Header("M", "", bytes(31), 1), None)


def test_the_frame_is_refused_by_version_length_and_size(monkeypatch):
    """Catches a reader that ignores the version, the length word, or MAX_BYTES."""
    data = bytearray(sf.encode(HEADER, None))
    struct.pack_into("<I", data, 8, sf.FORMAT_VERSION + 1)
    with pytest.raises(sf.StateFormatError, match=f"^state format version {sf.FORMAT_VERSION + 1}; "):
        sf.decode(bytes(data))
    good = sf.encode(HEADER, None)
    with pytest.raises(sf.StateFormatError, match=f"^the state says it has {len(good)} bytes, {len(good) + 1} were"):
        sf.decode(good + b"\0")
    monkeypatch.setattr(sf, "MAX_BYTES", len(good) - 1)
    with pytest.raises(sf.StateFormatError, match=f"^a state of {len(good)} bytes is over the {len(good) - 1} bytes"):
        sf.decode(good)
    monkeypatch.setattr(sf, "MAX_BYTES", len(good))
    assert sf.decode(good) == (HEADER, None)


_ARRAY = _bytes_of(np.array([1.0, 2.0]))
_SCALAR = _bytes_of(np.float32(1.0))
#: (a whole value, how many of its bytes are left, what the reader names, bytes it wanted).  A str's
#: or bytes' payload is refused by its length's check first (test_a_count_is_checked_...).
_CUT = [(_bytes_of(5), 4, "int", 8), (_bytes_of(0.5), 1, "float", 8), (_bytes_of(1j), 9, "complex", 16),
        (_bytes_of("ab"), 3, "str length", 4),
        (_bytes_of([1]), 2, "tuple/list count", 4), (_bytes_of({1: 2}), 4, "dict count", 4),
        (_bytes_of(sf.ObjectRecord("m", {})), 2, "class tag", 2), (_bytes_of(sf.Ref(0)), 1, "reference", 4),
        (_bytes_of(sf.Opaque("xy")), 2, "opaque tag", 2),
        (_ARRAY, 1, "array dtype", 2), (_ARRAY, 6, "array ndim", 1), (_ARRAY, 9, "array shape", 8),
        (_ARRAY, 17, "array size", 8), (_ARRAY, 26, "array data", 16),
        (_SCALAR, 1, "scalar dtype", 1), (_SCALAR, 5, "scalar size", 1), (_SCALAR, 7, "scalar", 4)]


@pytest.mark.parametrize("whole, kept, what, wanted", _CUT, ids=[c[2] for c in _CUT])
def test_a_value_cut_short_is_refused_naming_the_field_it_was_reading(whole, kept, what, wanted):
    """A value whose bytes end early (inside a whole, checksummed frame) is refused with the
    field's name, the bytes wanted and left, and the offset.  Catches a field read under
    another field's name (or a struct format's), and a read past the end."""
    cut = whole[:kept]
    list_of_it = b"l" + struct.pack("<I", 1) + cut
    wanted_at = _value_offset() + len(list_of_it) - (kept - _field_start(whole, what))
    left = len(list_of_it) + _value_offset() - wanted_at
    with pytest.raises(sf.StateFormatError,
                       match=f"^{what}: {wanted} bytes wanted, {left} left at offset {wanted_at}$"):
        sf.decode(_framed(list_of_it))


def _field_start(whole: bytes, what: str) -> int:
    """Where, in a value's bytes, the field named ``what`` starts (the table's layout)."""
    tag = whole[:1]
    if tag in (b"i", b"f", b"c", b"r") or what in ("str length", "tuple/list count", "dict count", "class tag",
                                                   "opaque tag", "array dtype", "scalar dtype"):
        return 1
    if tag == b"a":
        dtype_end = 1 + 2 + whole[1]
        return {"array ndim": dtype_end, "array shape": dtype_end + 1, "array size": dtype_end + 1 + 8,
                "array data": dtype_end + 1 + 8 + 8}[what]
    dtype_end = 1 + 1 + whole[1]
    return {"scalar size": dtype_end, "scalar": dtype_end + 1}[what]


def test_a_decoded_tree_is_written_back_to_the_same_bytes():
    """A record array (its dtype not plain: read as :class:`ArrayBytes`, its key the field
    description) and references, as read, written again: the same bytes, every field of the
    array's row at its documented place.  Catches the writer of a tree as read (an ArrayBytes,
    a Ref) off the table: the size word's width or place, the dtype's key, the shape."""
    record = np.array([(1.5, -2), (3.0, 7)], dtype=[("a", "<f8"), ("b", "<i4")])
    shared = [np.int16(4)]
    tree = {"r": record, "l": shared, "again": sf.SharedRef(shared), "rr": sf.SharedRef(record)}
    data = sf.encode(HEADER, tree)
    header, read = sf.decode(data)
    key = repr(record.dtype.descr)
    assert read["r"] == sf.ArrayBytes(key, (2,), record.tobytes())
    assert (read["again"], read["rr"]) == (sf.Ref(2), sf.Ref(1))       # dict 0, array 1, list 2
    assert sf.encode(header, read) == data
    raw = record.tobytes()
    array = (b"a" + _s(key, "<H") + struct.pack("<B", 1) + struct.pack("<Q", 2) + struct.pack("<Q", len(raw)) + raw)
    expected = (b"d" + struct.pack("<I", 4) + _bytes_of("r") + array + _bytes_of("l") + _bytes_of(read["l"])
                + _bytes_of("again") + _bytes_of(sf.Ref(2)) + _bytes_of("rr") + _bytes_of(sf.Ref(1)))
    assert data == _framed(expected)


def test_the_smallest_frame_passes_the_frame_checks_and_one_byte_less_is_no_state():
    """Magic (8 bytes), version (4), length (8) and the sha256 checksum (32): 52 bytes, a frame
    with an empty body, whose every check passes; it is then refused for the model identifier
    the header needs at offset 20.  51 bytes cannot be a state at all.  Training sample 4252's
    [31] (the frame's least length taken as ``<=``: the 52-byte frame refused as no state)."""

    least = 8 + 4 + 8 + 32
    body = sf.MAGIC + struct.pack("<IQ", sf.FORMAT_VERSION, least)
    frame = body + hashlib.sha256(body).digest()
    assert len(frame) == least
    with pytest.raises(sf.StateFormatError, match="^model identifier: 2 bytes wanted, 0 left at offset 20$"):
        sf.decode(frame)
    with pytest.raises(sf.StateFormatError, match=r"^not a serialised parcosim FMU state \(51 bytes starting "):
        sf.decode(frame[:-1])
