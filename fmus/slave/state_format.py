"""The bytes of a serialised parcosim FMU state (``fmi2SerializeFMUstate``): data, never code.

Reading a state calls no constructor, imports nothing and evaluates nothing: it yields
plain Python values, numeric numpy arrays made from a fixed list of dtypes, and the three
records below, which only *name* things.  What a name means is decided later, against
the live instance (:mod:`fmus.slave.state`).  docs/state.md specifies the format so that a
native FMU can write and read the same bytes.

Layout (all integers little-endian)::

    magic     8 bytes   b"PCSTATE\\0"
    version   u32       FORMAT_VERSION
    length    u64       of the whole buffer, checksum included
    model     str16     the model identifier (the slave class's name)
    guid      str16     the FMU's GUID ("" in process)
    config    32 bytes  SHA-256 of the configuration (fmus.slave.state.config_digest)
    layout    u32       the model's state layout version
    value               the state: one value (below), a dict of attribute names
    checksum  32 bytes  SHA-256 of every byte before it

A value is a one-byte tag and its payload:

====  =====================  ==============================================================
tag   value                  payload
====  =====================  ==============================================================
N     None                   none
T/F   True / False           none
i     int                    i64
f     float                  f64
c     complex                f64 real, f64 imaginary
s     str                    u32 length, UTF-8 bytes
y     bytes                  u32 length, bytes
a     numpy array            str16 dtype, u8 ndim, ndim x u64 shape, u64 nbytes, raw bytes (C order)
g     numpy scalar           str8 dtype, u8 nbytes, raw bytes
t/l   tuple / list           u32 count, count values
d     dict                   u32 count, count (key value, value) pairs
o     object of a class      str16 class tag, u32 count, count (str16 field, value) pairs
x     opaque (code)          str16 tag: a function, a class, a compiled kernel ...
r     reference              u32 index of an earlier t/l/d/o/a value (shared or cyclic)
====  =====================  ==============================================================

``str8``/``str16``: u8/u16 length, UTF-8 bytes.  Every count and length is checked against
the bytes left and against the limits below before anything is allocated.
"""
from __future__ import annotations

import hashlib
import math
import struct
from dataclasses import dataclass

import numpy as np

MAGIC = b"PCSTATE\0"
FORMAT_VERSION = 1
DIGEST_SIZE = 32
#: Limits a state must keep (a larger one is refused before it is read).
MAX_BYTES = 1 << 30
MAX_DEPTH = 64
MAX_VALUES = 1 << 24
MAX_NDIM = 8
#: The dtypes an array or scalar may have when the bytes alone say what it is.  A dtype
#: outside this list (records, objects) is read only against the live instance's array of
#: the same dtype (:class:`ArrayBytes`).
PLAIN_DTYPES = {np.dtype(t).str: np.dtype(t) for t in (
    "<f8", "<f4", "<c16", "<c8", "<i8", "<i4", "<i2", "i1", "<u8", "<u4", "<u2", "u1", "?")}


class StateFormatError(ValueError):
    """The bytes are not a well-formed parcosim FMU state; the message says where."""


@dataclass(frozen=True)
class Header:
    """What a state says it belongs to."""

    model: str
    guid: str
    config: bytes
    layout: int


@dataclass
class ObjectRecord:
    """An object's fields, by name, and its class's tag (``module.qualname``)."""

    tag: str
    fields: dict


@dataclass(frozen=True)
class Opaque:
    """Code the state refers to but does not carry (a function, a class, a compiled kernel)."""

    tag: str


@dataclass(frozen=True)
class Ref:
    """The ``index``-th list, dict, object or array of the state, met again (as read)."""

    index: int


@dataclass(frozen=True)
class SharedRef:
    """``node`` (a list, dict, :class:`ObjectRecord` or array of the tree being written), met
    again: written as a reference to where it was first written."""

    node: object


@dataclass
class ArrayBytes:
    """An array whose dtype (``dtype_key``) is not plain: its bytes, to be read as the live
    instance's array of that dtype."""

    dtype_key: str
    shape: tuple
    data: bytes


def dtype_key(dtype: np.dtype) -> str:
    """The dtype as the format names it: ``dtype.str`` for plain dtypes, the field
    description for records."""
    dtype = np.dtype(dtype)
    return dtype.str if dtype.fields is None else repr(dtype.descr)


# ---- writing ---------------------------------------------------------------------------


def encode(header: Header, value) -> bytes:
    """The bytes of ``value`` (a tree of the types above, as :mod:`fmus.slave.state` builds it)."""
    out = bytearray(MAGIC)
    out += struct.pack("<IQ", FORMAT_VERSION, 0)
    _str(out, header.model, "<H")
    _str(out, header.guid, "<H")
    if len(header.config) != DIGEST_SIZE:
        raise ValueError(f"the configuration digest has {len(header.config)} bytes, not {DIGEST_SIZE}")
    out += header.config
    out += struct.pack("<I", header.layout)
    Writer(out).value(value, 0)
    struct.pack_into("<Q", out, len(MAGIC) + 4, len(out) + DIGEST_SIZE)
    out += hashlib.sha256(out).digest()
    return bytes(out)


def _str(out: bytearray, text: str, size: str) -> None:
    data = text.encode()
    if len(data) >= 1 << (8 * struct.calcsize(size)):
        raise ValueError(f"string of {len(data)} bytes is too long for the state format: {text[:40]!r}...")
    out += struct.pack(size, len(data)) + data


class Writer:
    """Writes values (the table above) into ``out``."""

    def __init__(self, out: bytearray):
        self.out = out
        self.index = {}   # id(node) -> its index, for the references to it

    def indexed(self, node) -> None:
        """Number ``node`` as the reader will (lists, dicts, objects, arrays, in the order met)."""
        self.index[id(node)] = len(self.index)

    def value(self, v, depth: int) -> None:
        if depth > MAX_DEPTH:
            raise ValueError(f"the state is nested deeper than {MAX_DEPTH} levels")
        out = self.out
        if v is None:
            out += b"N"
        elif v is True or v is False:
            out += b"T" if v else b"F"
        elif type(v) is int:
            out += b"i" + struct.pack("<q", v)
        elif type(v) is float:
            out += b"f" + struct.pack("<d", v)
        elif type(v) is complex:
            out += b"c" + struct.pack("<dd", v.real, v.imag)
        elif type(v) is str:
            data = v.encode("utf-8", "surrogatepass")
            out += b"s" + struct.pack("<I", len(data)) + data
        elif type(v) is bytes:
            out += b"y" + struct.pack("<I", len(v)) + v
        elif isinstance(v, SharedRef):
            index = self.index.get(id(v.node))
            if index is None:
                raise ValueError("a reference to a value not written before it")
            out += b"r" + struct.pack("<I", index)
        elif isinstance(v, Ref):   # a tree as read, written again
            out += b"r" + struct.pack("<I", v.index)
        elif isinstance(v, ArrayBytes):
            self.indexed(v)
            out += b"a"
            _str(out, v.dtype_key, "<H")
            out += struct.pack("<B", len(v.shape)) + struct.pack(f"<{len(v.shape)}Q", *v.shape)
            out += struct.pack("<Q", len(v.data)) + v.data
        elif isinstance(v, Opaque):
            out += b"x"
            _str(out, v.tag, "<H")
        elif isinstance(v, np.ndarray):
            self.indexed(v)
            data = np.ascontiguousarray(v).tobytes()
            out += b"a"
            _str(out, dtype_key(v.dtype), "<H")
            out += struct.pack("<B", v.ndim) + struct.pack(f"<{v.ndim}Q", *v.shape) + struct.pack("<Q", len(data))
            out += data
        elif isinstance(v, np.generic):
            data = v.tobytes()
            out += b"g"
            _str(out, dtype_key(v.dtype), "<B")
            out += struct.pack("<B", len(data)) + data
        elif type(v) in (tuple, list):
            if type(v) is list:
                self.indexed(v)
            out += (b"t" if type(v) is tuple else b"l") + struct.pack("<I", len(v))
            for item in v:
                self.value(item, depth + 1)
        elif type(v) is dict:
            self.indexed(v)
            out += b"d" + struct.pack("<I", len(v))
            for key, item in v.items():
                self.value(key, depth + 1)
                self.value(item, depth + 1)
        elif isinstance(v, ObjectRecord):
            self.indexed(v)
            out += b"o"
            _str(out, v.tag, "<H")
            out += struct.pack("<I", len(v.fields))
            for name, item in v.fields.items():
                _str(out, name, "<H")
                self.value(item, depth + 1)
        else:
            raise TypeError(f"a {type(v).__name__} cannot be written into a state")


# ---- reading ---------------------------------------------------------------------------


def decode(data: bytes) -> tuple[Header, object]:
    """The header and the value of a serialised state.

    Raises
    ------
    StateFormatError
        The bytes are not a whole, unaltered state of this format; the message names
        what did not match (magic, version, length, checksum, or the value at an offset).
    """
    data = bytes(data)
    fixed = len(MAGIC) + 12
    if len(data) < fixed + DIGEST_SIZE or not data.startswith(MAGIC):
        raise StateFormatError(f"not a serialised parcosim FMU state ({len(data)} bytes starting "
                               f"{data[:16]!r}; a state starts with {MAGIC!r})")
    version, length = struct.unpack_from("<IQ", data, len(MAGIC))
    if version != FORMAT_VERSION:
        raise StateFormatError(f"state format version {version}; this FMU reads version {FORMAT_VERSION}")
    if length != len(data):
        raise StateFormatError(f"the state says it has {length} bytes, {len(data)} were given (truncated or padded)")
    if length > MAX_BYTES:
        raise StateFormatError(f"a state of {length} bytes is over the {MAX_BYTES} bytes allowed")
    body, checksum = data[:-DIGEST_SIZE], data[-DIGEST_SIZE:]
    if hashlib.sha256(body).digest() != checksum:
        raise StateFormatError("the state's checksum does not match its bytes (altered or corrupted)")
    reader = _Reader(body, fixed)
    model = reader.text("<H", "model identifier")
    guid = reader.text("<H", "GUID")
    config = reader.take(DIGEST_SIZE, "configuration digest")
    layout = reader.unpack("<I", "layout version")
    value = reader.value(0)
    if reader.pos != len(body):
        raise StateFormatError(f"{len(body) - reader.pos} bytes left over after the state's value at offset {reader.pos}")
    return Header(model, guid, config, layout), value


class _Reader:
    def __init__(self, data: bytes, pos: int):
        self.data, self.pos = data, pos
        self.indexed = 0   # values that references may name
        self.values = 0

    def fail(self, what: str):
        raise StateFormatError(f"{what} at offset {self.pos}")

    def take(self, n: int, what: str) -> bytes:
        if n < 0 or self.pos + n > len(self.data):
            self.fail(f"{what}: {n} bytes wanted, {len(self.data) - self.pos} left")
        chunk = self.data[self.pos:self.pos + n]
        self.pos += n
        return chunk

    def unpack(self, fmt: str, what: str):
        return struct.unpack(fmt, self.take(struct.calcsize(fmt), what))[0]

    def text(self, size: str, what: str) -> str:
        raw = self.take(self.unpack(size, what), what)
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError:
            self.fail(f"{what} is not UTF-8")

    def count(self, what: str, least_bytes: int = 1) -> int:
        n = self.unpack("<I", what)
        if n * least_bytes > len(self.data) - self.pos:
            self.fail(f"{what} {n} is more than the bytes left can hold")
        return n

    def value(self, depth: int):
        if depth > MAX_DEPTH:
            self.fail(f"values nested deeper than {MAX_DEPTH} levels")
        self.values += 1
        if self.values > MAX_VALUES:
            self.fail(f"more than {MAX_VALUES} values")
        tag = self.take(1, "value tag")
        if tag == b"N":
            return None
        if tag in (b"T", b"F"):
            return tag == b"T"
        if tag == b"i":
            return self.unpack("<q", "int")
        if tag == b"f":
            return self.unpack("<d", "float")
        if tag == b"c":
            return complex(*struct.unpack("<dd", self.take(16, "complex")))
        if tag == b"s":
            raw = self.take(self.count("str length"), "str")
            try:
                return raw.decode("utf-8", "surrogatepass")
            except UnicodeDecodeError:
                self.fail("a str that is not UTF-8")
        if tag == b"y":
            return self.take(self.count("bytes length"), "bytes")
        if tag == b"r":
            index = self.unpack("<I", "reference")
            if index >= self.indexed:
                self.fail(f"a reference to value {index} of {self.indexed} met so far")
            return Ref(index)
        if tag == b"x":
            return Opaque(self.text("<H", "opaque tag"))
        if tag == b"a":
            return self.array()
        if tag == b"g":
            return self.scalar()
        if tag in (b"t", b"l"):
            if tag == b"l":
                self.indexed += 1
            n = self.count("tuple/list count")
            items = [self.value(depth + 1) for _ in range(n)]
            return tuple(items) if tag == b"t" else items
        if tag == b"d":
            self.indexed += 1
            n = self.count("dict count", 2)
            result = {}
            for _ in range(n):
                key = self.value(depth + 1)
                if not _hashable_key(key):
                    self.fail(f"a dict key of type {type(key).__name__}")
                result[key] = self.value(depth + 1)
            return result
        if tag == b"o":
            self.indexed += 1
            class_tag = self.text("<H", "class tag")
            n = self.count("field count", 3)
            fields = {}
            for _ in range(n):
                name = self.text("<H", "field name")
                if name in fields:
                    self.fail(f"field {name!r} of {class_tag} given twice")
                fields[name] = self.value(depth + 1)
            return ObjectRecord(class_tag, fields)
        self.fail(f"unknown value tag {tag!r}")

    def array(self):
        self.indexed += 1
        key = self.text("<H", "array dtype")
        ndim = self.unpack("<B", "array ndim")
        if ndim > MAX_NDIM:
            self.fail(f"an array of {ndim} dimensions (at most {MAX_NDIM})")
        shape = struct.unpack(f"<{ndim}Q", self.take(8 * ndim, "array shape"))
        nbytes = self.unpack("<Q", "array size")
        raw = self.take(nbytes, "array data")
        dtype = PLAIN_DTYPES.get(key)
        if dtype is None:
            return ArrayBytes(key, shape, raw)
        if math.prod(shape) * dtype.itemsize != nbytes:
            self.fail(f"an array of shape {shape} and dtype {key} in {nbytes} bytes")
        return np.frombuffer(raw, dtype=dtype).reshape(shape).copy()

    def scalar(self):
        key = self.text("<B", "scalar dtype")
        dtype = PLAIN_DTYPES.get(key)
        if dtype is None:
            self.fail(f"a numpy scalar of dtype {key!r} (not one of {sorted(PLAIN_DTYPES)})")
        n = self.unpack("<B", "scalar size")
        if n != dtype.itemsize:
            self.fail(f"a {key} scalar of {n} bytes")
        return np.frombuffer(self.take(n, "scalar"), dtype=dtype)[0]


def _hashable_key(key) -> bool:
    if key is None or type(key) in (bool, int, float, str, bytes):
        return True
    return type(key) is tuple and all(_hashable_key(k) for k in key)
