"""The pieces of the native loop's image (fmus/native/loopimage.py), each against an independent
reading: pointer offsets read back through ctypes, C declarations parsed from a header written
here, initialisers evaluated back to the values, buffers found within the documented depth.
No FMU is built: these run in a second."""
from __future__ import annotations

import ctypes
import re
import types

import numpy as np
import pytest

from fmus.cosim.compiled import NotCompilable
from fmus.native import loopimage
from fmus.native.loopimage import (_Arenas, _words_only, c_type_of, candidates, initialiser, pointer_fields,
                                   refusal_name, struct_types)

CALLBACK = ctypes.CFUNCTYPE(ctypes.c_double, ctypes.c_double)


class Inner(ctypes.Structure):
    _fields_ = [("a", ctypes.c_double), ("p", ctypes.POINTER(ctypes.c_double)), ("n", ctypes.c_int)]


class Outer(ctypes.Structure):
    _fields_ = [("k", ctypes.c_int), ("f", CALLBACK), ("pair", Inner * 2), ("s", ctypes.c_char_p),
                ("v", ctypes.c_void_p), ("x", ctypes.c_double * 3), ("inner", Inner)]


def _filled():
    """An Outer whose every pointer holds its own address (distinct, known) and whose numbers are set."""
    o = Outer()
    for k, target in enumerate([o.pair[0], o.pair[1], o.inner]):
        target.a, target.n = 0.1 * (k + 1) + 0.2, -7 * (k + 1)
    o.k, o.x[:] = 2**31 - 1, [1 / 3, -0.0, 1e-300]
    return o


def test_pointer_fields_are_every_pointer_at_its_offset():
    """Catches a pointer missed (in a nested structure, an array of structures, a function or
    char pointer) or one given the offset of another field: each (offset, name) is read back
    through ctypes at that offset, holding what was stored in the field of that name."""
    o = _filled()
    o.v = 0x1000
    ctypes.c_void_p.from_buffer(o, Outer.s.offset).value = 0x2000
    for k, target in enumerate([o.pair[0], o.pair[1]]):
        ctypes.c_void_p.from_buffer(target, Inner.p.offset).value = 0x3000 + 0x1000 * k
    ctypes.c_void_p.from_buffer(o.inner, Inner.p.offset).value = 0x5000
    ctypes.c_void_p.from_buffer(o, Outer.f.offset).value = 0x6000
    found = list(pointer_fields(Outer))
    assert [offset for offset, _ in found] == sorted(offset for offset, _ in found)
    assert len(found) == 6 and len({offset for offset, _ in found}) == 6
    read = {name: [] for _, name in found}
    for offset, name in found:
        read[name].append(ctypes.c_void_p.from_buffer(o, offset).value)
    assert read == {"f": [0x6000], "pairp": [0x3000, 0x4000], "s": [0x2000], "v": [0x1000], "innerp": [0x5000]}
    assert list(pointer_fields(Inner, base=40)) == [(40 + Inner.p.offset, "p")]
    assert list(pointer_fields(ctypes.c_double * 4)) == []


HEADER = """\
/* a comment with a struct: typedef struct { int zz; } Commented; */
#include <stddef.h>
typedef struct pc_a {
    double a;            // a comment: typedef struct { int yy; } Line;
    int b[3];
    const double *c, *d;
    void (*fn)(const double *x, size_t n);
    double (* const g)(void);
    double m[2][4];
} PcA;
typedef struct { double a; int b[3]; const double *c, *d; void (*fn)(const double *x, size_t n);
                 double (*const g)(void); double m[2][4]; } PcTwin;

typedef struct {
    double q;
} PcB;
"""


def test_struct_types_reads_members_in_order_outside_comments(tmp_path, monkeypatch):
    """Catches a header's comments read as declarations, a member missed (after a comma, an
    array, a function pointer, a const one) or two types with the same members not both listed."""
    (tmp_path / "pc_test.h").write_text(HEADER)
    (tmp_path / "pc_test.c").write_text("typedef struct { double not_a_header; } PcC;\n")
    monkeypatch.setattr(loopimage, "KERNELS", tmp_path)
    assert struct_types() == {("a", "b", "c", "d", "fn", "g", "m"): ["PcA", "PcTwin"], ("q",): ["PcB"]}


def test_the_kernels_headers_give_each_compiled_context_one_type():
    """Catches a parse of the kernels' headers that loses their structures (the real files)."""
    found = struct_types()
    named = {name for names in found.values() for name in names}
    for header in loopimage.KERNELS.glob("*.h"):
        text = re.sub(r"/\*.*?\*/", "", header.read_text(), flags=re.S)
        for name in re.findall(r"}\s*(\w+)\s*;", text):
            if re.search(rf"typedef\s+struct\s*\w*\s*\{{[^{{}}]*\}}\s*{name}\s*;", text):
                assert name in named, (header.name, name)


def test_c_type_of_is_the_one_type_with_these_members():
    """Catches a context matched to no or several C types without refusing, naming the fields."""
    assert c_type_of(Inner, {("a", "p", "n"): ["PcInner"], ("a", "p"): ["Other"]}) == "PcInner"
    with pytest.raises(NotCompilable, match=r"^context Inner \(fields a, p, n\): no C types"):
        c_type_of(Inner, {("a", "p"): ["Other"]})
    with pytest.raises(NotCompilable, match=r"2 C types of the kernels' headers have these members \(X, Y\)$"):
        c_type_of(Inner, {("a", "p", "n"): ["X", "Y"]})


def _parse(text):
    """{.a = 1.0, .b = {...}} as a dict, {1, 2} as a list, each value as its text."""
    tokens = re.findall(r"\.\w+ =|[{},]|[^{},\s][^{},]*", text)
    pos = 0

    def value():
        nonlocal pos
        if tokens[pos] == "{":
            pos += 1
            named, items = {}, []
            while tokens[pos] != "}":
                if tokens[pos].startswith(".") and tokens[pos].endswith(" ="):
                    key = tokens[pos][1:-2]
                    pos += 1
                    named[key] = value()
                else:
                    items.append(value())
                if tokens[pos] == ",":
                    pos += 1
            pos += 1
            return named if named else items
        token = tokens[pos].strip()
        pos += 1
        return token

    return value()


def test_an_initialiser_gives_back_every_value_exactly():
    """Catches a double written with fewer digits than its repr (0.30000000000000004), a field
    left out or given another's value, an array element or a nested structure's misplaced, or a
    pointer passed to the callback with another address or name."""
    o = _filled()
    ctypes.c_void_p.from_buffer(o, Outer.v.offset).value = 0x1234
    ctypes.c_void_p.from_buffer(o.pair[1], Inner.p.offset).value = 0x5678
    seen = []

    def pointer(value, what):
        seen.append((value, what))
        return "0" if value is None else f"P{value:x}"

    tree = _parse(initialiser(Outer, ctypes.addressof(o), pointer))
    assert list(tree) == [name for name, *_ in Outer._fields_]
    assert int(tree["k"]) == 2**31 - 1 and [float(x) for x in tree["x"]] == [1 / 3, -0.0, 1e-300]
    assert str(float(tree["x"][1])) == "-0.0"
    for got, inner in zip(tree["pair"] + [tree["inner"]], [o.pair[0], o.pair[1], o.inner]):
        assert (float(got["a"]), int(got["n"])) == (inner.a, inner.n)
    assert tree["v"] == "P1234" and tree["pair"][1]["p"] == "P5678" and tree["pair"][0]["p"] == "0"
    assert (0x1234, "Outer.v") in seen and (0x5678, "Inner.p") in seen and len(seen) == 6


def test_an_initialiser_refuses_what_is_not_portable():
    """Catches an integer beyond 32 bits (a C long on Windows), a 64-bit integer field or a bit
    field accepted, or a refusal that does not name the field and the value."""
    class Wide(ctypes.Structure):
        _fields_ = [("ok", ctypes.c_long), ("big", ctypes.c_longlong)]

    class Neg(ctypes.Structure):
        _fields_ = [("low", ctypes.c_int)]

    class Bits(ctypes.Structure):
        _fields_ = [("flags", ctypes.c_int, 3)]

    class Odd(ctypes.Structure):
        _fields_ = [("b", ctypes.c_bool)]

    w = Wide(-2**31, 2**31)
    with pytest.raises(NotCompilable, match=r"^Wide\.big = 2147483648: beyond 32 bits"):
        initialiser(Wide, ctypes.addressof(w), None)
    w.big = 2**31 - 1
    assert initialiser(Wide, ctypes.addressof(w), None) == "{.ok = -2147483648, .big = 2147483647}"
    assert initialiser(Neg, ctypes.addressof(Neg(-5)), None) == "{.low = -5}"
    with pytest.raises(NotCompilable, match=r"^Bits\.flags: a bit field$"):
        initialiser(Bits, ctypes.addressof(Bits()), None)
    with pytest.raises(NotCompilable, match=r"^Odd\.b: a field of ctypes type c_bool has no portable initialiser"):
        initialiser(Odd, ctypes.addressof(Odd()), None)


@pytest.mark.parametrize("buffer, ok", [
    (np.zeros(3), True), (np.zeros(2, dtype=np.int64), True), (np.zeros(2, dtype=np.uint64), True),
    (np.zeros(4, dtype=np.float32), False), (np.zeros(2, dtype=np.int32), False), (np.zeros(2, dtype=complex), False),
    ((ctypes.c_double * 3)(), True), ((ctypes.c_int64 * 2 * 2)(), True), ((ctypes.c_int * 2)(), False),
    (Inner(), False), ((ctypes.c_float * 2)(), False)], ids=lambda v: type(v).__name__ if not isinstance(v, bool) else str(v))
def test_a_data_buffer_must_be_of_8_byte_words(buffer, ok):
    """Catches a buffer whose bytes depend on the byte order (4-byte elements, a structure with
    an int or a pointer) accepted into the data arena, or a buffer of words refused."""
    if ok:
        _words_only(buffer, "b")
    else:
        with pytest.raises(NotCompilable, match=r"^b: a buffer of \w+, not of 8-byte words"):
            _words_only(buffer, "b")


def test_a_structure_of_words_is_words():
    """Catches a structure (or an array of structures) of doubles refused as not of words."""
    class Words(ctypes.Structure):
        _fields_ = [("a", ctypes.c_double), ("b", ctypes.c_int64 * 2)]

    class Nested(ctypes.Structure):
        _fields_ = [("w", Words * 2), ("c", ctypes.c_uint64)]

    _words_only(Nested(), "n")
    _words_only((Words * 3)(), "n")


def _chain(depth, leaf):
    """An object whose attribute ``a`` ``depth - 1`` times then ``leaf`` reaches ``leaf``."""
    obj = types.SimpleNamespace(leaf=leaf)
    for _ in range(depth - 1):
        obj = types.SimpleNamespace(a=obj)
    return obj


def test_candidates_reach_exactly_depth_levels():
    """Catches a walk that goes deeper than ``depth`` levels (a level not counted) or stops short."""
    leaf = np.arange(4.0)
    address = leaf.__array_interface__["data"][0]
    for depth in (1, 3, 8):
        assert address in candidates([_chain(depth, leaf)], depth=depth)
        assert address not in candidates([_chain(depth + 1, leaf)], depth=depth)


class _Slotted:
    __slots__ = ("buf",)

    def __init__(self, buf):
        self.buf = buf


def test_candidates_walk_containers_slots_and_views_to_their_owner():
    """Catches a buffer missed in a dict, list, tuple, set or __slots__, a view given its own extent
    instead of the whole array's it views, or a ctypes object given another extent."""
    whole = np.arange(10.0)
    view = whole[2:5]
    cbuf = (ctypes.c_double * 3)()
    held = np.zeros(2)
    found = candidates([{"k": [(view,)]}, {_Slotted(cbuf)}, types.SimpleNamespace(fn=lambda: held)])
    size, owner = found[whole.__array_interface__["data"][0]]
    assert size == 80 and owner is view       # the whole array's extent, the object reached
    assert found[ctypes.addressof(cbuf)][0] == 24 and found[ctypes.addressof(cbuf)][1] is cbuf
    assert held.__array_interface__["data"][0] not in found          # a plain function is not walked
    assert len(found) == 2


def test_a_block_is_the_largest_buffer_holding_the_address():
    """Catches an address resolved to a smaller buffer inside a larger one, a wrong offset, a
    block found twice, overlapping buffers accepted, or an address outside every buffer
    accepted; the refusals name the address."""
    arenas = _Arenas({1000: (64, "a"), 1032: (80, "b"), 1016: (8, "c"), 2000: (0, "empty")})
    assert arenas.empty == {2000}
    block, offset = arenas.block_of(1040, "p")
    assert (block.address, block.size, offset) == (1032, 80, 8)
    again, offset = arenas.block_of(1111, "q")
    assert again is block and offset == 79 and len(arenas.blocks) == 1
    with pytest.raises(NotCompilable, match=r"^r: buffers at 0x3e8 and 0x408 overlap$"):
        arenas.block_of(1000, "r")
    with pytest.raises(NotCompilable, match=r"^s: address 0x70c is in no buffer the loop's components hold$"):
        arenas.block_of(1804, "s")
    with pytest.raises(NotCompilable, match=r"address 0x3e7 is in no buffer"):
        arenas.block_of(999, "t")


def test_buffers_that_only_touch_are_two_blocks_and_one_byte_of_overlap_is_refused():
    """Blocks are half-open [address, address + size): a buffer starting where another ends
    does not overlap it, and an address at a block's end belongs to the next one.  Catches
    ``<`` made ``<=`` on either side of the overlap test or in the look-up of a block."""
    arenas = _Arenas({1000: (16, "a"), 1016: (16, "b"), 1031: (8, "c")})
    first, offset = arenas.block_of(1000, "p")
    assert (first.address, first.size, offset) == (1000, 16, 0)
    second, offset = arenas.block_of(1016, "q")                    # the first's end: the next buffer
    assert second is not first and (second.address, second.size, offset) == (1016, 16, 0)
    assert arenas.block_of(1015, "r") == (first, 15)
    with pytest.raises(NotCompilable, match=r"^s: buffers at 0x407 and 0x3f8 overlap$"):
        arenas.block_of(1035, "s")                                 # [1031, 1039) takes 1031 of [1016, 1032)
    touching = _Arenas({1016: (16, "b"), 1000: (16, "a")})
    assert touching.block_of(1020, "t")[0].address == 1016
    assert touching.block_of(1004, "u")[0].address == 1000           # ends where the first begins
    assert len(touching.blocks) == 2


def test_a_refusal_code_is_named_as_its_header_names_it():
    """Catches a kernel's refusal named from another kernel's header or by another code."""
    header = (loopimage.KERNELS / "law.h").read_text()
    name, text = re.search(r"(PC_LAW_\w+)\s*=\s*8\b,?\s*/\*\s*(.*?)\s*\*/", header).groups()
    assert refusal_name("pc_law_io", 8) == f"refusal {name}: {text}"
    assert refusal_name("pc_law_io", 12345) == "refusal code 12345"
    assert refusal_name("pc_nosuchkernel_io", 8) == "refusal code 8"


def _pointer_expressions(ctype, address, tree):
    """(pointer value, its C expression, the field's ctypes type) of every pointer field of the
    context ``ctype`` at ``address``, the expressions read from the parsed initialiser ``tree``."""
    for name, ftype, *_ in ctype._fields_:
        at, node = address + getattr(ctype, name).offset, tree[name]
        if issubclass(ftype, ctypes.Structure):
            yield from _pointer_expressions(ftype, at, node)
        elif issubclass(ftype, ctypes.Array):
            size = ctypes.sizeof(ftype._type_)
            for k, item in enumerate(node):
                if issubclass(ftype._type_, ctypes.Structure):
                    yield from _pointer_expressions(ftype._type_, at + k * size, item)
                elif loopimage._is_pointer(ftype._type_):
                    yield ctypes.c_void_p.from_address(at + k * size).value, item, ftype._type_
        elif loopimage._is_pointer(ftype):
            yield ctypes.c_void_p.from_address(at).value, node, ftype


@pytest.fixture(scope="module", params=["bench", "drives_in_plant"])
def loop_and_image(request, tmp_path_factory):
    """The image of the native loop's scene (tests/conftest.py LOOP_SCENE; with its drives inside
    the plant: a context that points to another), made in process as ``export-fmu --native``
    makes it, with the stepper's values before it and the plan it was taken from."""
    import json

    from fmus.native import loopbuild
    from scenarios.scenes import drives_in_plant, get_scene
    from tests.conftest import LOOP_SCENE

    scene = get_scene(LOOP_SCENE)
    scene = scene if request.param == "bench" else drives_in_plant(scene, substeps=4)
    system = loopbuild.closed_loop_system(scene.system)
    resources = tmp_path_factory.mktemp("loop_image")
    (resources / loopbuild.SYSTEM_FILE).write_text(json.dumps({"role": "loop", "plant": "plant",
                                                                "system": loopbuild.system_to_dict(system)}))
    slave = loopbuild.ClosedLoop(instance_name=loopbuild.MODEL, resources=str(resources))
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    stepper = slave.core.stepper
    values, slots, k = list(stepper.values), dict(stepper.slots), stepper.k
    plans = []
    real = loopimage.Plan

    def capture(*args):
        plans.append(real(*args))
        return plans[-1]

    loopimage.Plan = capture
    try:
        image = loopimage.loop_image(system, stepper)
    finally:
        loopimage.Plan = real
    return image, values, slots, k, plans[0]


def test_each_pointer_of_a_member_context_is_its_buffer_or_context_in_the_image(loop_and_image):
    """Catches a context's pointer written as another place of the data arena (its offset in
    its buffer lost or negated: the words there are not the ones it points to) or as another
    context (``&s->b<k>`` of another C type), or a member given another context: every pointer
    of every member's context, read from the live context, against the image.  Only words the
    run never changed are compared (the image is the state before the run)."""
    image, _, _, _, plan = loop_and_image
    fixed = np.zeros(image.values_word, dtype=bool)
    for start, n in image.fixed:
        fixed[start:start + n] = True
    types = struct_types()
    compared = contexts = 0
    owners = {ctypes.addressof(c): m[3] for m, c in zip(image.members, plan._contexts)}
    for member, context in zip(image.members, plan._contexts):
        ctype_name, text = image.contexts[member[3]]
        assert ctype_name == c_type_of(type(context), types)
        for value, expression, ftype in _pointer_expressions(type(context), ctypes.addressof(context), _parse(text)):
            if value is None:
                assert expression == "0"
            elif expression.startswith("&s->b"):
                target = int(expression[5:])
                assert target != member[3] and 0 <= target < len(image.contexts), expression
                assert target == owners.get(value, target), expression     # a member's context: that one
                contexts += 1
            elif expression.startswith("(void *)(data + "):
                word = int(expression[len("(void *)(data + "):-1])
                assert 0 <= word < image.values_word, expression
                if fixed[word]:
                    assert image.data[8 * word:8 * word + 8] == ctypes.string_at(value, 8), expression
                    compared += 1
    assert compared > 10
    assert contexts > 0 or len(image.contexts) == len(image.members)
def test_the_loop_image_lays_out_values_states_and_the_step_count(loop_and_image):
    """Catches the stepper's values, a member's state ``x`` or the step count written elsewhere
    than the words the image names (or not written): each read back from the data arena, and
    the members' states one after another between the values and the step count."""
    image, values, slots, k, _ = loop_and_image
    words = np.frombuffer(image.data, dtype=np.float64)
    assert len(image.data) % 8 == 0 and image.slots == slots
    assert image.n_values == len(values)
    assert np.array_equal(words[image.values_word:image.values_word + image.n_values], values)
    starts = [m[4] for m in image.members] + [image.steps_word]
    assert starts[0] == image.values_word + image.n_values and all(a < b for a, b in zip(starts, starts[1:]))
    assert words[image.steps_word] == k and len(words) == image.steps_word + 1
    assert [m[3] for m in image.members] == list(range(len(image.members)))      # each its own context
    plant = image.members[-1]
    x = words[plant[4]:starts[-1]]
    assert plant[0] == "plant" and np.all(np.isfinite(x)) and np.any(x != 0.0)


def test_the_loop_images_pointers_and_fixed_words_stay_in_the_data_arena(loop_and_image):
    """Catches a context's pointer into the data arena past its buffers (into the values, the
    states) or between words, a context of a C type the headers do not have, and the fixed
    words (the configuration the FMU state's check compares) not maximal sorted runs of the
    buffers' words."""
    image, *_ = loop_and_image
    types = {name for names in struct_types().values() for name in names}
    for ctype, text in image.contexts:
        assert ctype in types
        for word in re.findall(r"\(void \*\)\(data \+ (\d+)\)", text):
            assert int(word) < image.values_word
        assert not re.search(r"&s->b(\d+)", text) or all(int(b) < len(image.contexts)
                                                         for b in re.findall(r"&s->b(\d+)", text))
    runs = image.fixed
    assert runs and runs[0][0] >= 0 and sum(n for _, n in runs) < image.values_word
    for (a, n), (b, _) in zip(runs, runs[1:]):
        assert n > 0 and a + n < b                  # sorted, disjoint, not adjacent (maximal)
    assert runs[-1][0] + runs[-1][1] <= image.values_word


def test_kernel_functions_names_every_exported_kernel_function_at_its_address():
    """Catches kernel_functions missing or inventing a function of the kernels' library, or
    mapping a name to another function's address (the loop image would then call the wrong
    step): its names are the non-static functions declared in kernels/src, each at the address
    a separate load of the library gives."""
    import kernels
    declared = set()
    for source in sorted(loopimage.KERNELS.glob("*.[ch]")):
        text = re.sub(r"/\*.*?\*/", "", source.read_text(), flags=re.S)
        declared |= set(re.findall(r"^(?!static)[A-Za-z_][\w \*]*?\b(pc_\w+)\s*\(", text, flags=re.M))
    functions = loopimage.kernel_functions()
    assert sorted(functions.values()) == sorted(declared)
    again = ctypes.CDLL(kernels.library()._name)
    for address, name in functions.items():
        assert address and ctypes.cast(getattr(again, name), ctypes.c_void_p).value == address, name
