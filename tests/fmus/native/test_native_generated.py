"""What fmus/native/build.py generates for a native FMU, read back by its consumers: the C table
(model_table.c, model_config.h) compiled and printed by C, every value compared with what was
given to the last bit; buildDescription.xml read by fmpy against FMI 3.0's schema; the
CMakeLists and the compile command naming exactly the sources."""
from __future__ import annotations

import math
import shutil
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

from fmus.native.build import HERE, KERNELS, build_description, cmake_lists, compile_command, generate, kernel_files

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler (cc)")

ROWS = [
    {"name": "u", "vr": 0, "type": "Real", "causality": "input", "tunable": False, "start": 1 / 3},
    {"name": "gain", "vr": 3, "type": "Real", "causality": "parameter", "tunable": True, "start": -0.0},
    {"name": "n", "vr": 4, "type": "Integer", "causality": "parameter", "tunable": False, "start": -2147483647},
    {"name": "ctrl.lam", "vr": 5, "type": "Real", "causality": "parameter", "tunable": False, "start": 5e-324},
    {"name": "on", "vr": 7, "type": "Boolean", "causality": "parameter", "tunable": False, "start": True},
    {"name": "label", "vr": 8, "type": "String", "causality": "parameter", "tunable": False,
     "start": 'say "hi"\\ \n\ttab'},
    {"name": "y", "vr": 9, "type": "Real", "causality": "output", "tunable": False, "start": math.inf},
    {"name": "z", "vr": 11, "type": "Real", "causality": "output", "tunable": False, "start": -math.inf},
    {"name": "m", "vr": 12, "type": "Integer", "causality": "output", "tunable": False, "start": 7},
    {"name": "off", "vr": 13, "type": "Boolean", "causality": "input", "tunable": False, "start": False},
    {"name": "w", "vr": 14, "type": "Real", "causality": "output", "tunable": False, "start": math.nan},
]
SCALARS = {"data_words": 12, "accepted_steps": "a multiple of 1 ms", "limit": 1e300, "most": -math.inf}
ARRAYS = {"design": np.arange(18.0).reshape(3, 6) / 7.0 - 1.0, "names": ["q1", 'q"2'], "gains": [0.5, -2.0, 3.25]}
TYPES, CAUSALITIES = ("Real", "Integer", "Boolean", "String"), ("input", "output", "parameter")

MAIN = r"""
#include <stdio.h>
#include <string.h>
#include <stdint.h>
#include "model_config.h"
#include "pcn_model.h"

static void bits(double x) { uint64_t u; memcpy(&u, &x, 8); printf("%016llx", (unsigned long long)u); }
static void text(const char *s) { for (; s && *s; s++) printf("%02x", (unsigned char)*s); printf(" "); }

int main(void) {
    for (int k = 0; k < pcn_n_variables; k++) {
        const pcn_variable *v = &pcn_variables[k];
        printf("var "); text(v->name);
        printf("%u %d %d %d %d ", v->vr, (int)v->type, (int)v->causality, v->tunable, v->slot);
        bits(v->start); printf(" "); text(v->start_string); printf("\n");
    }
    printf("slots %d %d %d %d\n", pcn_n_slots[0], pcn_n_slots[1], pcn_n_slots[2], pcn_n_slots[3]);
    printf("guid "); text(pcn_guid); printf("\n");
    printf("identifier "); text(PCN_IDENTIFIER); printf("\n");
    printf("data_words %ld\n", (long)PCN_DATA_WORDS);
    printf("accepted_steps "); text(PCN_ACCEPTED_STEPS); printf("\n");
    printf("limit "); bits(PCN_LIMIT); printf("\nmost "); bits(PCN_MOST); printf("\n");
    printf("slot_u %d slot_y %d slot_w %d slot_label %d slot_off %d\n", PCN_SLOT_u, PCN_SLOT_y, PCN_SLOT_w,
           PCN_SLOT_label, PCN_SLOT_off);
    printf("design %d", PCN_DESIGN_WORDS);
    for (int k = 0; k < PCN_DESIGN_WORDS; k++) { printf(" "); bits(pcn_design[k]); }
    printf("\ngains %d", PCN_GAINS_WORDS);
    for (int k = 0; k < PCN_GAINS_WORDS; k++) { printf(" "); bits(pcn_gains[k]); }
    printf("\nnames %d", PCN_NAMES_COUNT);
    for (int k = 0; k < PCN_NAMES_COUNT; k++) { printf(" "); text(pcn_names[k]); }
    printf("\n");
    return 0;
}
"""


def _bits(x: float) -> str:
    return struct.pack(">d", x).hex()


def _hex(s: str) -> str:
    return s.encode().hex()


@pytest.fixture(scope="module")
def printed(tmp_path_factory):
    """What C reads from the generated table, line by line (tag -> fields)."""
    where = tmp_path_factory.mktemp("generated")
    header, table = generate("Probe", ROWS, SCALARS, ARRAYS, "{guid-\"1\"}")
    (where / "model_config.h").write_text(header)
    (where / "model_table.c").write_text(table)
    (where / "main.c").write_text(MAIN)
    subprocess.run(["cc", "-std=c11", "-Wall", "-Werror", f"-I{where}", f"-I{HERE}", str(where / "main.c"),
                    str(where / "model_table.c"), "-o", str(where / "probe")], check=True, capture_output=True)
    out = subprocess.run([str(where / "probe")], check=True, capture_output=True, text=True).stdout
    lines = [line.split(" ") for line in out.splitlines()]
    return [line for line in lines if line[0] == "var"], {line[0]: line[1:] for line in lines if line[0] != "var"}


def test_the_c_table_holds_every_variable_as_given(printed):
    """Catches a variable's name, value reference, type, causality, tunability or start value
    written otherwise than given (a double not to the last bit, -0.0 as 0.0, an infinity, a
    String start's quote, backslash or newline), or slots not numbered per type in table order."""
    variables, _ = printed
    assert len(variables) == len(ROWS)
    slots = {t: 0 for t in TYPES}
    for (_, name, vr, kind, causality, tunable, slot, start, string, *_), row in zip(variables, ROWS):
        assert (name, int(vr), TYPES[int(kind)], CAUSALITIES[int(causality)], bool(int(tunable))) == \
            (_hex(row["name"]), row["vr"], row["type"], row["causality"], row["tunable"])
        assert int(slot) == slots[row["type"]]
        slots[row["type"]] += 1
        if row["type"] == "String":
            assert (string, struct.unpack(">d", bytes.fromhex(start))[0]) == (_hex(row["start"]), 0.0)
        elif isinstance(row["start"], float) and math.isnan(row["start"]):
            assert math.isnan(struct.unpack(">d", bytes.fromhex(start))[0]) and string == ""
        else:
            assert (start, string) == (_bits(float(row["start"])), "")


def test_the_c_header_holds_the_counts_scalars_and_arrays(printed):
    """Catches per-type slot counts, the GUID, a scalar (string, integer, double) or an array
    element (the fourth of a line, the last) written otherwise, an array's length wrong, or a
    variable's slot macro naming another slot."""
    _, tags = printed
    assert [int(n) for n in tags["slots"]] == [sum(r["type"] == t for r in ROWS) for t in TYPES]
    assert tags["guid"][0] == _hex('{guid-"1"}') and tags["identifier"][0] == _hex("Probe")
    assert int(tags["data_words"][0]) == 12 and tags["accepted_steps"][0] == _hex("a multiple of 1 ms")
    assert tags["limit"] == [_bits(1e300)] and tags["most"] == [_bits(-math.inf)]
    assert tags["slot_u"] == ["0", "slot_y", "3", "slot_w", "5", "slot_label", "0", "slot_off", "1"]
    design = ARRAYS["design"].ravel()
    assert int(tags["design"][0]) == design.size and tags["design"][1:] == [_bits(x) for x in design]
    assert tags["names"] == ["2", _hex("q1"), "", _hex('q"2'), ""]
    assert tags["gains"] == ["3"] + [_bits(x) for x in ARRAYS["gains"]]      # a plain list of numbers


def test_the_build_description_is_valid_fmi3_and_names_the_sources(tmp_path):
    """Catches a buildDescription.xml that FMI 3.0's schema refuses (an element in the wrong
    place: the math library inside the source file set), another model identifier, or a source
    left out or added."""
    from fmpy.model_description import read_build_description

    sources = ["pcn_core.c", "model_table.c", "fmi2_native.c"]
    path = tmp_path / "buildDescription.xml"
    path.write_text(build_description("Probe", sources))
    (configuration,) = read_build_description(str(path), validate=True)
    assert configuration.modelIdentifier == "Probe"
    assert [f for s in configuration.sourceFileSets for f in s.sourceFiles] == sources


def test_the_cmake_lists_and_the_compile_command_take_the_sources(tmp_path):
    """Catches a CMakeLists that builds another target or from other files, or a compile command
    that leaves a C file of the folder out or takes a header as a source."""
    text = cmake_lists("Probe", ["a.c", "b.c"], fmi_version=3)
    assert "add_library(Probe SHARED a.c b.c)\n" in text and "FMI 3.0 headers" in text
    assert "project(Probe C)" in text and "target_link_libraries(Probe m)" in text
    for name in ("b.c", "a.c", "x.h"):
        (tmp_path / name).write_text("")
    command = compile_command(tmp_path, tmp_path / "out.so", compiler="gcc")
    assert command[0] == "gcc" and command[command.index("-o") + 1] == str(tmp_path / "out.so")
    assert [c for c in command if c.endswith((".c", ".h"))] == [str(tmp_path / "a.c"), str(tmp_path / "b.c")]
    assert f"-I{tmp_path}" in command and "-lm" in command and "-ffp-contract=off" in command


@pytest.mark.parametrize("kernel", ["law.c", "actuated.c", "wheeled.c"])
def test_a_kernels_files_are_what_the_compiler_includes(kernel):
    """Catches a header a kernel includes (directly or through another header) left out of a
    native FMU's sources, or a file named that is not one: the compiler's own list of the
    dependencies (``cc -MM``) is the reference."""
    listed = subprocess.run(["cc", "-MM", f"-I{KERNELS}", str(KERNELS / kernel)], check=True, capture_output=True,
                            text=True).stdout
    expected = {KERNELS / p.name for p in map(Path, listed.split(":", 1)[1].replace("\\\n", " ").split())}
    assert set(kernel_files([kernel])) == expected and len(kernel_files([kernel])) == len(expected)
    assert kernel_files([kernel]) == sorted(expected)
