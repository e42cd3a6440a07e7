"""The compiled loop of a system as build data: ``export-fmu --native`` (docs/native.md).

:mod:`fmus.compiled` sets a system's loop up in Python (each component's kernel buffers,
initialised by its slave) and hands ``pc_loop_run`` (kernels/src/loop.c) a plan of pointers.
:func:`loop_image` takes that plan apart into data a C file can carry: every buffer the
members' contexts point to, as bytes (the **data** arena, saved in the FMU state), the
contexts themselves as C initialisers (:attr:`LoopImage.contexts`: each context's fields by
name, its pointers as expressions into the instance's arenas; the compiler lays the
**scratch** arena out, so no byte layout of this machine's C ABI travels), the plan's
integer arrays, the stepper's values and each member's ``x``.  The data arena holds 8-byte
words only (float64 or 64-bit integers), written as their bit patterns: the same on any
machine with IEEE doubles, whatever its byte order.  Nothing here knows a model: a context
is read through its ctypes fields and its C type found by its field names among the
kernels' headers, a pointer resolved to the buffer that holds its address (found by walking
the adapters, their slaves and the contexts) or to a function of the kernels' library.

Then the loop runs over the system's stop time on the Python side (the same C kernels):
a member that declines a step there (the compiled mode would take that step in Python)
refuses the build, and the data words that never change over that run are the
configuration the FMU state's check compares (:attr:`LoopImage.fixed`).
"""
from __future__ import annotations

import ctypes
import re
import subprocess
from dataclasses import dataclass, field

import numpy as np

import kernels

from fmus.cosim.compiled import NotCompilable, Plan, _adapters
from fmus.cosim.stepper import Stepper
from fmus.native.build import KERNELS, _c_double

WORD = 8
#: A context's integer fields must hold in 32 bits: a C ``long`` is 4 bytes on Windows.
PORTABLE_INT = (-2**31, 2**31 - 1)


@dataclass
class Block:
    """One buffer: its address and length in bytes, and whether it holds pointers (a context)."""

    address: int
    size: int
    ctype: type | None = None     # the ctypes Structure of a context
    offset: int = 0               # data blocks: in the data arena, bytes; contexts: their index


@dataclass
class LoopImage:
    """A system's compiled loop as data (module docstring).  Offsets are in bytes unless named
    ``*_word``."""

    data: bytes = b""                 # the data arena's initial bytes
    contexts: list = field(default_factory=list)      # (C type, initialiser) of scratch context k (b<k>)
    functions: list = field(default_factory=list)     # names of the kernel functions pointed to
    members: list = field(default_factory=list)       # (name, model, kernel, its context's index, x word)
    groups: list = field(default_factory=list)        # (substeps, end)
    inputs: list = field(default_factory=list)        # per member: [(index in x, slot)]
    outputs: list = field(default_factory=list)
    values_word: int = 0
    n_values: int = 0
    steps_word: int = 0               # the steps taken k (a whole double): the loop's time is k h
    slots: dict = field(default_factory=dict)         # signal -> slot
    fixed: list = field(default_factory=list)         # (first word, words) never changed by the run


def _is_pointer(ctype) -> bool:
    return issubclass(ctype, (ctypes.c_void_p, ctypes._Pointer, ctypes._CFuncPtr, ctypes.c_char_p))


def pointer_fields(ctype, base: int = 0):
    """(byte offset, field name) of every pointer in the ctypes type ``ctype`` (nested
    structures and arrays included)."""
    if issubclass(ctype, ctypes.Structure):
        for name, ftype, *_ in ctype._fields_:
            for offset, sub in pointer_fields(ftype, base + getattr(ctype, name).offset):
                yield offset, name + sub
    elif issubclass(ctype, ctypes.Array):
        for k in range(ctype._length_):
            yield from pointer_fields(ctype._type_, base + k * ctypes.sizeof(ctype._type_))
    elif _is_pointer(ctype):
        yield base, ""


def struct_types() -> dict:
    """(member names, in order) -> [C type names] of every ``typedef struct {...} NAME;``
    of the kernels' headers (kernels/src/*.h; no nested braces)."""
    found = {}
    for header in sorted(KERNELS.glob("*.h")):
        source = re.sub(r"//[^\n]*", "", re.sub(r"/\*.*?\*/", "", header.read_text(), flags=re.S))
        for body, name in re.findall(r"typedef\s+struct\s*\w*\s*\{([^{}]*)\}\s*(\w+)\s*;", source):
            names = []
            for decl in filter(None, (d.strip() for d in body.split(";"))):
                pointer = re.search(r"\(\s*\*\s*(?:const\s+)?(\w+)\s*\)", decl)   # a function pointer
                names += [pointer[1]] if pointer else [re.search(r"(\w+)\s*(?:\[[^\]]*\]\s*)*$", piece.strip())[1]
                                                       for piece in decl.split(",")]
            found.setdefault(tuple(names), []).append(name)
    return found


def c_type_of(ctype, types: dict) -> str:
    """The kernels' C type of the ctypes Structure ``ctype``: the one whose members are its
    fields, by name and in order; NotCompilable when none or several are."""
    names = tuple(name for name, *_ in ctype._fields_)
    found = types.get(names, [])
    if len(found) != 1:
        raise NotCompilable(f"context {ctype.__name__} (fields {', '.join(names)}): "
                            f"{'no' if not found else len(found)} C types of the kernels' headers have these members"
                            + (f" ({', '.join(found)})" if found else ""))
    return found[0]


def initialiser(ctype, address: int, pointer) -> str:
    """A C designated initialiser of the ctypes Structure at ``address``: each field by name,
    doubles exactly (repr), integers checked to hold in 32 bits, each pointer as
    ``pointer(address)`` gives it (an expression)."""
    def value(ftype, at, what):
        if issubclass(ftype, ctypes.Structure):
            return initialiser(ftype, at, pointer)
        if issubclass(ftype, ctypes.Array):
            size = ctypes.sizeof(ftype._type_)
            return "{" + ", ".join(value(ftype._type_, at + k * size, f"{what}[{k}]")
                                   for k in range(ftype._length_)) + "}"
        if _is_pointer(ftype):
            return pointer(ctypes.c_void_p.from_address(at).value, f"{ctype.__name__}.{what}")
        if ftype in (ctypes.c_double, ctypes.c_float):
            return _c_double(ftype.from_address(at).value)
        if ftype in (ctypes.c_int, ctypes.c_long, ctypes.c_longlong, ctypes.c_short, ctypes.c_uint, ctypes.c_ulong):
            number = ftype.from_address(at).value
            if not PORTABLE_INT[0] <= number <= PORTABLE_INT[1]:
                raise NotCompilable(f"{ctype.__name__}.{what} = {number}: beyond 32 bits (a C long on Windows)")
            return str(number)
        raise NotCompilable(f"{ctype.__name__}.{what}: a field of ctypes type {ftype.__name__} has no portable "
                            "initialiser here")

    fields = []
    for name, ftype, *bits in ctype._fields_:
        if bits:
            raise NotCompilable(f"{ctype.__name__}.{name}: a bit field")
        fields.append(f".{name} = {value(ftype, address + getattr(ctype, name).offset, name)}")
    return "{" + ", ".join(fields) + "}"


def _words_only(obj, what: str) -> None:
    """Refuse a data buffer that is not in 8-byte words (float64, 64-bit integers): another
    element size would depend on the target's byte order."""
    if isinstance(obj, np.ndarray):
        ok = obj.dtype.itemsize == WORD and obj.dtype.kind in "fiu"
        kind = str(obj.dtype)
    else:
        ctype = obj if isinstance(obj, type) else type(obj)
        while issubclass(ctype, ctypes.Array):
            ctype = ctype._type_
        fields = [f[1] for f in getattr(ctype, "_fields_", [(None, ctype)])]
        ok = all(t in (ctypes.c_double, ctypes.c_int64, ctypes.c_uint64) or
                 (issubclass(t, (ctypes.Structure, ctypes.Array)) and _words_ok(t)) for t in fields)
        kind = ctype.__name__
    if not ok:
        raise NotCompilable(f"{what}: a buffer of {kind}, not of 8-byte words (float64, 64-bit integers): its bytes "
                            "would depend on the target's byte order")


def _words_ok(ctype) -> bool:
    try:
        _words_only(ctype, "")
    except NotCompilable:
        return False
    return True


def _extent(obj):
    """(address, bytes) of the memory ``obj`` owns or views: a numpy array's outermost array, a ctypes object."""
    if isinstance(obj, np.ndarray):
        while isinstance(obj.base, np.ndarray):
            obj = obj.base
        return obj.__array_interface__["data"][0], obj.nbytes
    if isinstance(obj, ctypes._SimpleCData | ctypes.Structure | ctypes.Array | ctypes.Union):
        return ctypes.addressof(obj), ctypes.sizeof(obj)
    return None


def candidates(roots, depth: int = 8) -> dict:
    """address -> (bytes, object) of every numpy array and ctypes object reachable from
    ``roots`` through attributes, slots, lists, tuples and dicts (``depth`` levels)."""
    found, seen, todo = {}, set(), [(r, 0) for r in roots]
    while todo:
        obj, level = todo.pop()
        if id(obj) in seen or level > depth or obj is None or isinstance(obj, (str, bytes, int, float, type)):
            continue
        seen.add(id(obj))
        extent = _extent(obj)
        if extent is not None:
            address, size = extent
            if address not in found or size > found[address][0]:
                found[address] = (size, obj)
            if isinstance(obj, np.ndarray):
                continue
        children = []
        if isinstance(obj, dict):
            children = list(obj.values())
        elif isinstance(obj, (list, tuple, set, frozenset)):
            children = list(obj)
        else:
            children = list(getattr(obj, "__dict__", {}).values())
            for cls in type(obj).__mro__:
                for name in getattr(cls, "__slots__", ()):
                    children.append(getattr(obj, name, None))
        todo += [(c, level + 1) for c in children if not callable(c) or hasattr(c, "__dict__")]
    return found


def kernel_functions() -> dict:
    """address -> name of every function the kernels' library exports."""
    lib = kernels.library()
    listed = subprocess.run(["nm", "-D", "--defined-only", lib._name], capture_output=True, text=True, check=True)
    names = [line.split()[-1] for line in listed.stdout.splitlines() if line.split()[1:2] == ["T"]]
    return {ctypes.cast(getattr(lib, n), ctypes.c_void_p).value: n for n in names}


class _Arenas:
    """The blocks found from the contexts, placed in the data or the scratch arena."""

    def __init__(self, found: dict):
        self.found = sorted((a, s, o) for a, (s, o) in found.items() if s)
        self.empty = {a for a, (s, _) in found.items() if not s}   # empty arrays: read by nothing
        self.blocks: list[Block] = []
        self.functions = None

    def block_of(self, address: int, what: str) -> tuple[Block, int]:
        """The block holding ``address`` (the largest candidate that contains it) and the offset in it."""
        for b in self.blocks:
            if b.address <= address < b.address + b.size:
                return b, address - b.address
        best = None
        for start, size, obj in self.found:
            if start <= address < start + size and (best is None or size > best[1]):
                best = (start, size, obj)
        if best is None:
            raise NotCompilable(f"{what}: address {address:#x} is in no buffer the loop's components hold")
        start, size, obj = best
        for b in self.blocks:
            if b.address < start + size and start < b.address + b.size:
                raise NotCompilable(f"{what}: buffers at {start:#x} and {b.address:#x} overlap")
        ctype = type(obj) if isinstance(obj, ctypes.Structure) and any(pointer_fields(type(obj))) else None
        block = Block(start, size, ctype)
        self.blocks.append(block)
        return block, address - start


def _pad(data: bytes) -> bytes:
    return data + bytes(-len(data) % WORD)


def loop_image(system, stepper: Stepper) -> LoopImage:
    """The compiled loop of ``system`` over ``stepper`` (initialised at t = 0) as data; the
    loop is then run to the system's stop time (module docstring).  Raises NotCompilable for
    what the compiled loop or this image does not cover, naming why."""
    _adapters()
    plan = Plan(system, stepper)
    arenas = _Arenas(candidates([plan.adapters, plan._contexts, stepper.instances]))
    image = LoopImage()
    contexts = []
    for adapter, context in zip(plan.adapters, plan._contexts):
        block, at = arenas.block_of(ctypes.addressof(context), f"component {adapter.name}'s context")
        if block.ctype is None:
            block.ctype = type(context)
        contexts.append((adapter, block, at))
    # every context the members' contexts point to (and those they point to) found
    pending = list(arenas.blocks)
    while pending:
        block = pending.pop()
        for offset, name in pointer_fields(block.ctype):
            value = ctypes.c_void_p.from_address(block.address + offset).value
            if value is None or not any(s <= value < s + n for s, n, _ in arenas.found):
                continue
            before = len(arenas.blocks)
            target, _ = arenas.block_of(value, f"{block.ctype.__name__}.{name}")
            if len(arenas.blocks) > before and target.ctype is not None:
                pending.append(target)
    data, scratch = bytearray(), [b for b in arenas.blocks if b.ctype is not None]
    objects = {start: obj for start, _, obj in arenas.found}
    for b in arenas.blocks:
        if b.ctype is None:
            _words_only(objects[b.address], f"a buffer of {b.size} bytes")
            b.offset = len(data)
            data += _pad(ctypes.string_at(b.address, b.size))
    for k, b in enumerate(scratch):
        b.offset = k

    def pointer(value, what):
        if value is None:
            return "0"
        inside = [b for b in arenas.blocks if b.address <= value < b.address + b.size]
        if inside and inside[0].ctype is not None:
            if value != inside[0].address:
                raise NotCompilable(f"{what}: points {value - inside[0].address} bytes into a context, a layout "
                                    "of this machine's C ABI")
            return f"&s->b{inside[0].offset}"
        if inside:
            at = inside[0].offset + value - inside[0].address
            if at % WORD:
                raise NotCompilable(f"{what}: points between the 8-byte words of a buffer")
            return f"(void *)(data + {at // WORD})"
        if value in arenas.empty:       # an empty array (no motors...): any valid address
            return "(void *)data"
        if arenas.functions is None:
            arenas.functions = kernel_functions()
        if value not in arenas.functions:
            raise NotCompilable(f"{what}: {value:#x} is neither a buffer of the loop's components nor a function "
                                "of the kernels")
        fn = arenas.functions[value]
        if fn not in image.functions:
            image.functions.append(fn)
        return fn

    types = struct_types()
    image.contexts = [(c_type_of(b.ctype, types), initialiser(b.ctype, b.address, pointer)) for b in scratch]
    image.values_word = len(data) // WORD
    image.n_values = len(stepper.values)
    data += np.asarray(stepper.values, dtype=np.float64).tobytes()
    for adapter, block, at in contexts:
        if at:
            raise NotCompilable(f"component {adapter.name}'s context is {at} bytes into another")
        image.members.append((adapter.name, adapter.model, adapter.kernel, block.offset, len(data) // WORD))
        data += adapter.x.astype(np.float64).tobytes()
    image.steps_word = len(data) // WORD
    data += np.float64(stepper.k).tobytes()
    for member in plan.loop.members:
        image.inputs.append(member.inputs)
        image.outputs.append(member.outputs)
    ends = plan.loop._arrays["group_end"].tolist()
    image.groups = list(zip(plan.loop._arrays["group_substeps"].tolist(), ends))
    image.data, image.slots = bytes(data), dict(stepper.slots)
    image.fixed = _run_to_stop(system, plan, stepper, arenas, image)
    return image


def refusal_name(kernel: str, code: int) -> str:
    """``code`` of the kernel ``pc_<model>_io`` as its header names it (``PC_LAW_TABLE_HOLE: its
    cell has a left-out corner``), else the number."""
    prefix = f"PC_{kernel.split('_')[1].upper()}_"
    pattern = re.compile(rf"({prefix}\w+)\s*=\s*{int(code)}\b,?\s*/\*\s*(.*?)\s*\*/")
    for header in sorted(KERNELS.glob("*.h")):
        found = pattern.search(header.read_text())
        if found:
            return f"refusal {found[1]}: {found[2]}"
    return f"refusal code {code}"


def _run_to_stop(system, plan, stepper, arenas, image) -> list:
    """Run the loop over the system's stop time (Python's side, the same kernels); a
    member that declines a step refuses the build.  Returns the (first word, words) runs of
    data words the run never changed."""
    blocks = [b for b in arenas.blocks if b.ctype is None]
    views = [np.frombuffer((ctypes.c_uint8 * b.size).from_address(b.address), dtype=np.uint8) for b in blocks]
    initial = [v.copy() for v in views]
    changed = [np.zeros(b.size, dtype=bool) for b in blocks]
    values = np.array(stepper.values, dtype=float)
    record = np.zeros((system.steps + 1, len(stepper.record_slots)))
    for k in range(system.steps):      # step by step: a word that changes and comes back is run state
        stop = plan.run(values, record, k, k + 1, stepper.start_time, system.step)
        if stop.member >= 0:
            a = plan.adapters[stop.member]
            raise NotCompilable(f"component {a.name} ({a.model}): its kernel {a.kernel} declines the step from t = "
                                f"{stop.time!r} s ({refusal_name(a.kernel, stop.refusal.code)}), which the compiled "
                                "mode takes in Python; a native FMU has no Python to take it")
        for c, v, v0 in zip(changed, views, initial):
            c |= v != v0
    same = np.ones(image.values_word, dtype=bool)
    for b, c in zip(blocks, changed):
        words = np.pad(c, (0, -b.size % WORD)).reshape(-1, WORD).any(axis=1)
        same[b.offset // WORD:b.offset // WORD + words.size] = ~words
    runs, k = [], 0
    while k < same.size:
        if same[k]:
            start = k
            while k < same.size and same[k]:
                k += 1
            runs.append((start, k - start))
        else:
            k += 1
    return runs
