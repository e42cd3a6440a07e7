"""The native ClosedLoop's sources carry no byte layout of the exporting machine (issue 28,
item 2): its contexts travel as C initialisers by field name (``loop_contexts.h``,
``pcn_loop_fill`` in ``loop_table.c``), its data as 8-byte words, so its ``sources/``
compile for another ABI and run there as shipped.

Oracles: the shipped binary's outputs, bit for bit, from a binary compiled from the FMU's
sources with every context struct laid out otherwise (members in reverse order after a
padding member: what another ABI's sizes and alignments do to a byte image, where the
previous byte image was misread); and a compile of the sources for the i386 ABI (4-byte
pointers and ``long``), where the byte image's static assertion stopped the build.
"""
from __future__ import annotations

import re
import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import simulate_fmu

from fmus.native.build import CFLAGS, compile_command, fmi_headers, platform_folder

#: The strict warnings of the kernels' own build (tests/fmus/native/test_native_build.py).
STRICT = ("-Wall", "-Wextra", "-Werror", "-Wshadow")


def _unzipped(fmu, folder):
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder


def _contexts(sources) -> list:
    """The C types of the scratch arena's contexts (loop_contexts.h)."""
    return re.findall(r"^\s+(\w+) b\d+;", (sources / "loop_contexts.h").read_text(), re.M)


def _laid_out_otherwise(sources, types) -> int:
    """Rewrite each ``typedef struct {...} T;`` of ``types`` in the headers of ``sources``:
    a padding member first, then the members in reverse order.  Returns how many."""
    done = 0
    for header in sources.glob("*.h"):
        text = header.read_text()
        for name in set(types):
            pattern = re.compile(r"typedef struct \{([^{}]*)\}\s*" + name + r"\s*;")
            found = pattern.search(text)
            if not found:
                continue
            body = re.sub(r"/\*.*?\*/", "", found[1], flags=re.S)
            members = [m.strip() for m in body.split(";") if m.strip()]
            new = "typedef struct {\n    char layout_probe[12];\n" + "".join(f"    {m};\n" for m in reversed(members))
            text = text[:found.start()] + new + f"}} {name};" + text[found.end():]
            done += 1
        header.write_text(text)
    return done


def test_the_loop_compiled_with_its_contexts_laid_out_otherwise_runs_as_shipped(native_loop_fmu, tmp_path):
    """Catches generated loop code that depends on its structs' memory layout (offsets hard-coded instead
    of named fields): reordered fields under strict flags must give the same run."""
    fmu = _unzipped(native_loop_fmu, tmp_path / "fmu")
    sources = fmu / "sources"
    types = _contexts(sources)
    assert len(set(types)) >= 5, types          # derivator, law, trajectory, observer, drive, plant
    assert _laid_out_otherwise(sources, types) == len(set(types))
    binary = fmu / "binaries" / platform_folder() / "ClosedLoop.so"
    binary.unlink()
    command = compile_command(sources, binary)
    subprocess.run([command[0], *STRICT, *command[1:]], check=True, capture_output=True)
    shipped = simulate_fmu(str(native_loop_fmu), stop_time=0.3, output_interval=1e-3, step_size=1e-3)
    again = simulate_fmu(str(fmu), stop_time=0.3, output_interval=1e-3, step_size=1e-3)
    assert np.max(np.abs(shipped["x"])) > 0.01          # the robot is on its circle, not at 0
    for name in shipped.dtype.names:
        assert np.array_equal(shipped[name], again[name]), name


def _i386_compiler(tmp_path):
    """(cc, extra flags) that compile C for i386 here, or None.  Without a 32-bit C library,
    the x86-64 headers serve (bits/ is shared; an empty gnu/stubs-32.h stands for the
    missing one): enough to compile, not to link."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        return None
    probe = tmp_path / "probe.c"
    probe.write_text("#include <math.h>\n#include <string.h>\n#include <stdio.h>\n"
                     "_Static_assert(sizeof(void *) == 4 && sizeof(long) == 4, \"i386\");\n"
                     "double f(double x) { char b[8]; snprintf(b, 8, \"%g\", x); return sqrt(x) + (double)strlen(b); }\n")
    shim = tmp_path / "shim"
    (shim / "gnu").mkdir(parents=True)
    (shim / "gnu" / "stubs-32.h").write_text("/* compile only: no 32-bit C library here */\n")
    for extra in ([], [f"-I{shim}", "-I/usr/include/x86_64-linux-gnu"]):
        flags = ["-m32", "-msse2", "-mfpmath=sse", *extra]
        if subprocess.run([cc, *flags, "-c", str(probe), "-o", str(tmp_path / "probe.o")],
                          capture_output=True).returncode == 0:
            return cc, flags
    return None


def test_the_loop_sources_compile_for_the_i386_abi(native_loop_fmu, tmp_path):
    """4-byte pointers and ``long``: the contexts' layout is the compiler's (SSE2 doubles:
    the kernels need double evaluation, pc_trig.h)."""
    found = _i386_compiler(tmp_path)
    if found is None:
        pytest.skip("no C compiler for -m32 here")
    cc, flags = found
    sources = _unzipped(native_loop_fmu, tmp_path / "fmu") / "sources"
    out = tmp_path / "o32"
    out.mkdir()
    for source in sorted(sources.glob("*.c")):
        done = subprocess.run([cc, *flags, *CFLAGS, *STRICT, f"-I{sources}", f"-I{fmi_headers()}", "-c", str(source),
                               "-o", str(out / f"{source.stem}.o")], capture_output=True, text=True)
        assert done.returncode == 0, (source.name, done.stderr[-2000:])
    kind = subprocess.run(["file", str(out / "loop_table.o")], capture_output=True, text=True).stdout
    assert "32-bit" in kind and "80386" in kind, kind
