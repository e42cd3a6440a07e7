"""The C kernels under AddressSanitizer and UndefinedBehaviorSanitizer.

The kernels' library is built again with ``-fsanitize=address,undefined`` (kernels/build.py
``--sanitize``), and the kernels' own tests (``tests/kernels/test_kernels_*.py``, the compiled loop's
included) run in a subprocess that loads that build
(``$PARCOSIM_KERNELS_LIB``) with the ASan runtime preloaded: an out-of-bounds access, a use
after free or undefined behaviour (signed overflow, a misaligned load, a bad shift) in any
kernel those tests reach aborts the run and fails this test.  Python's own allocations are
not checked for leaks (``detect_leaks=0``); they go through malloc (``PYTHONMALLOC``) so
that the end of every buffer a kernel gets has ASan's redzone behind it.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from kernels import build
from tests.support.paths import ROOT



def _runtime(name: str) -> str | None:
    try:
        path = subprocess.run([build.compiler(), f"-print-file-name={name}"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (build.NoCompiler, subprocess.CalledProcessError):
        return None
    return path if os.path.isabs(path) and os.path.exists(path) else None


ASAN = _runtime("libasan.so")
#: Loaded after the ASan runtime so that its __cxa_throw interceptor finds the real one: a
#: C++ extension that throws (matplotlib's, which python-control imports with ``plant``)
#: otherwise stops the process in ASan's CHECK.
STDCXX = _runtime("libstdc++.so.6")
pytestmark = [pytest.mark.slow, pytest.mark.tools,
              pytest.mark.skipif(ASAN is None, reason="the C compiler has no AddressSanitizer runtime")]


def _sanitized_env(library: Path) -> dict:
    return {**os.environ, "PARCOSIM_KERNELS_LIB": str(library), "LD_PRELOAD": " ".join(filter(None, (ASAN, STDCXX))),
            # Python's small-object allocator would hide a buffer's end from ASan's redzones
            "PYTHONMALLOC": "malloc",
            "ASAN_OPTIONS": "detect_leaks=0:exitcode=99",
            "UBSAN_OPTIONS": "halt_on_error=1:print_stacktrace=1:exitcode=98"}


def test_the_harness_catches_an_out_of_bounds_write(tmp_path):
    # Which wrong code would the harness miss if the runtime were not active? This one.
    """Catches a sanitizer harness whose runtime is inactive (an out-of-bounds write would pass)."""
    source = tmp_path / "oob.c"
    source.write_text("void poke(double *a, int n) { a[n] = 1.0; }\n")
    library = tmp_path / "liboob.so"
    subprocess.run([build.compiler(), *build.FLAGS, *build.SANITIZE, str(source), "-o", str(library)], check=True)
    script = ("import ctypes, numpy as np; a = np.zeros(4); lib = ctypes.CDLL(%r); "
              "buf = (ctypes.c_double * 4)(); lib.poke(buf, 4)" % str(library))
    run = subprocess.run([sys.executable, "-c", script], env=_sanitized_env(library), capture_output=True, text=True)
    assert run.returncode == 99 and "buffer-overflow" in run.stderr, run.stderr


def test_the_kernels_tests_pass_under_asan_and_ubsan(tmp_path):
    """Catches out-of-bounds accesses, leaks and undefined behaviour in the C kernels."""
    library = build.build(tmp_path / "libparcosim_kernels.so", sanitize=True)
    # Not the memcheck test: valgrind cannot run a process with the ASan runtime preloaded (ASan
    # exits 99 at start), and with -x its failure stopped the run before the files after it.
    tests = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "tests" / "kernels").glob("test_kernels_*.py")
                   if p.name != "test_kernels_memcheck.py")
    assert len(tests) > 5, tests            # none would run the whole suite under the sanitizers
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-s", "-p", "no:cacheprovider", *tests],
                         cwd=ROOT, env=_sanitized_env(library), capture_output=True, text=True)
    tail = (run.stdout + run.stderr)[-4000:]
    assert run.returncode == 0, tail
    assert "ERROR: AddressSanitizer" not in run.stderr and "runtime error:" not in run.stderr, tail
