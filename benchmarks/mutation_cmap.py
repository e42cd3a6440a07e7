"""Which tests execute which line of the C kernels (``kernels/src/*.c``): the C half of the map
of :mod:`benchmarks.mutation_map` (issue 31, session 41).

coverage.py sees Python lines only.  A C map's run builds the copy's kernels with gcc's
``--coverage`` at ``-O0`` (every line its own code, none merged away by the optimiser) into one
library (:func:`build_library`) and runs the tests with ``$PARCOSIM_KERNELS_LIB`` naming it,
so every process that loads the kernels (the test process, an FMU run in fmpy's child, a CLI
subprocess, an exported FMU's bundle) loads that build.  The library exports two hooks beside
the kernels, ``pc_coverage_reset`` and ``pc_coverage_dump`` (libgcov's ``__gcov_reset`` and
``__gcov_dump``, hidden in a shared library).  :mod:`benchmarks.mutation_timing` calls them
around each test in the test process and points ``$GCOV_PREFIX`` at a folder of that test's
own (``<dir>/<n>``) for the test's duration: its in-process counts are dumped there after the
test, and a process it starts inherits the variable and dumps there at its exit (whenever that
is: the folders are read after the whole run), so a subprocess's lines count as the test's
that started it, as :data:`benchmarks.mutation_map`'s ``$PARCOSIM_TEST_CONTEXT`` does for
Python.  Lines run outside a test (collection) go to ``<dir>/outside`` and to no test.
:func:`build` then reads each folder's counts with ``gcov --json-format``: a line with a
non-zero count is executed by that test.

Not seen: a native FMU (fmus/native) compiles the kernels' sources into its own binary, and a
process that ends without running its exit handlers (``os._exit``, a signal) dumps nothing.
"""
from __future__ import annotations

import gzip
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from benchmarks import mutation_map
from kernels import build as kbuild

#: The environment variable naming the folder of the per-test gcov folders (read by the timing plugin).
GCOV_DIR = "PARCOSIM_MUTATION_GCOV"
#: Where a map names the lines of ``kernels/src/<name>.c``.
PREFIX = "kernels/src/"
#: The coverage build's extra source: libgcov's reset and dump, exported under names of ours.
HOOKS = ("extern void __gcov_reset(void);\nextern void __gcov_dump(void);\n"
         "void pc_coverage_reset(void);\nvoid pc_coverage_dump(void);\n"
         "void pc_coverage_reset(void) { __gcov_reset(); }\nvoid pc_coverage_dump(void) { __gcov_dump(); }\n")


def build_library(sources: Path, where: Path) -> Path:
    """Compile each ``.c`` of ``sources`` with :data:`kernels.build.FLAGS` at ``-O0`` and
    ``--coverage`` into ``where/<name>.o`` (its ``.gcno`` beside it) and link them with the
    :data:`HOOKS` into ``where/libparcosim_kernels.so``.  Raises
    ``subprocess.CalledProcessError`` when the compiler refuses."""
    where.mkdir(parents=True, exist_ok=True)
    cc = kbuild.compiler()
    flags = [f for f in kbuild.FLAGS if f not in ("-O3", "-shared")] + ["-O0", "--coverage"]
    objects = []
    for source in sorted(sources.glob("*.c")):
        obj = where / (source.stem + ".o")
        subprocess.run([cc, *flags, f'-DPC_SOURCES_HASH="{kbuild.sources_hash()}"', f"-I{sources}", "-c",
                        str(source.resolve()), "-o", str(obj)], check=True)
        objects.append(str(obj))
    hooks = where / "pc_coverage_hooks.c"
    hooks.write_text(HOOKS)
    subprocess.run([cc, "-fPIC", "-O0", "-c", str(hooks), "-o", str(where / "pc_coverage_hooks.o")], check=True)
    library = where / kbuild.LIBRARY.name
    subprocess.run([cc, "-shared", "--coverage", *objects, str(where / "pc_coverage_hooks.o"), "-o", str(library),
                    "-lm"], check=True)
    return library


def executed_lines(folder: Path, objects: Path) -> dict:
    """``{"kernels/src/<name>.c": {line, ...}}``: the lines with a non-zero count in the
    ``.gcda`` files of ``folder`` (the notes, ``.gcno``, are in ``objects``)."""
    data = sorted(folder.glob("*.gcda"))
    if not data:
        return {}
    for gcda in data:
        note = gcda.with_suffix(".gcno")
        if not note.exists():
            note.symlink_to(objects / note.name)
    out = subprocess.run(["gcov", "--json-format", "--stdout", *[p.name for p in data]], cwd=folder,
                         check=True, capture_output=True, text=True).stdout
    lines = {}
    for document in out.splitlines():
        if not document.strip():
            continue
        for entry in json.loads(document)["files"]:
            name = Path(entry["file"]).name
            if not name.endswith(".c"):
                continue           # a header's inline functions: not mutated
            run = {line["line_number"] for line in entry["lines"] if line["count"] > 0}
            if run:
                lines.setdefault(PREFIX + name, set()).update(run)
    return lines


def build(copy: Path, tests: list, out: Path, log=sys.stdout) -> dict:
    """Run ``tests`` (files, relative to ``copy``) in ``copy`` against the coverage build of its
    kernels; write the map of their C lines to ``out`` (the format of
    :func:`benchmarks.mutation_map.build`; ``outside`` empty) and return it."""
    work = Path(tempfile.mkdtemp(prefix="parcosim_cmap_"))
    try:
        objects = work / "objects"
        library = build_library(copy / "kernels" / "src", objects)
        folders = work / "gcov"
        shutil.copy2(Path(__file__).with_name("mutation_timing.py"), work / "parcosim_mutation_timing.py")
        times = work / "times.json"
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", PARCOSIM_MUTATION_TIMES=str(times),
                   PARCOSIM_CACHE=str(work / "cache"), PARCOSIM_KERNELS_LIB=str(library),
                   GCOV_PREFIX_STRIP=str(len(objects.resolve().parts) - 1), **{GCOV_DIR: str(folders)},
                   PYTHONPATH=os.pathsep.join([str(copy), str(work), *mutation_map._other_paths()]))
        command = mutation_map.pytest_command(copy, "-p", "parcosim_mutation_timing", *tests)
        done = subprocess.run(command, cwd=copy, env=env, stdout=log, stderr=subprocess.STDOUT)
        timing = json.loads(times.read_text()) if times.exists() else {"tests": {}, "shared": {}, "failed": [],
                                                                       "gcov": {}}
        names, lines = [], {}
        for number, test in sorted(timing.get("gcov", {}).items(), key=lambda item: int(item[0])):
            for source, run in executed_lines(folders / number, objects).items():
                if not names or names[-1] != test:
                    names.append(test)
                for line in run:
                    lines.setdefault(source, {}).setdefault(str(line), []).append(len(names) - 1)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    record = {"commit": mutation_map.head(), "returncode": done.returncode, "tests": names,
              "cost": [timing["tests"].get(name, {}).get("seconds", 0.0) for name in names],
              "slow": [timing["tests"].get(name, {}).get("slow", False) for name in names],
              "shared_of": [timing["tests"].get(name, {}).get("shared", []) for name in names],
              "shared": timing["shared"], "all_tests": timing["tests"], "failed": timing["failed"],
              "lines": lines, "outside": {}}
    out.parent.mkdir(parents=True, exist_ok=True)
    with gzip.open(out, "wt") as stream:
        json.dump(record, stream)
    return record
