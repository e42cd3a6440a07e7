"""The 5R's C kernel calls under valgrind's memcheck, on the library this process loaded.

tests/kernels/test_sanitizers.py builds the kernels again with AddressSanitizer from the sources;
this test needs no build: a child process under memcheck loads the library in use (a build of
other sources, ``$PARCOSIM_KERNELS_LIB``, included) and makes the plant's calls (step with and
without motors, three in a row so the kept trigonometry is read; derivative, residual,
report, projection, inverse terms) on buffers of exactly their documented sizes, every output
then read.  Any invalid read or write, or any use of an uninitialised value, that memcheck
traces to the library fails it.  Python's allocations go through malloc (``PYTHONMALLOC``) so
each buffer's end is a heap block's; the loader's own reports (glibc's, not the library's) are
not counted."""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import kernels
from plant import IntegratorSettings, PlantSimulator, fast5r, get_preset

VALGRIND = shutil.which("valgrind")
pytestmark = [pytest.mark.slow, pytest.mark.tools,
              pytest.mark.skipif(VALGRIND is None, reason="valgrind is not installed")]

#: Two motors (joint, R, L, kt, ke, b, mu, omega_eps), as tests/kernels/test_oracles_kernels.py's.
MOTORS = [[0.0, 1.1, 6.7e-4, 0.056, 0.051, 1.2e-4, 0.04, 0.5], [1.0, 2.3, 1.9e-3, 0.081, 0.077, 3.1e-4, 0.02, 0.2]]

CHILD = r"""
import ctypes, json, sys
lib = ctypes.CDLL(sys.argv[1])
d = json.load(open(sys.argv[2]))
v, i, f = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
malloc = ctypes.CDLL(None).malloc
malloc.restype, malloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t]
def empty(n):   # a heap block of exactly n doubles, uninitialised
    return ctypes.cast(malloc(8 * n), ctypes.POINTER(ctypes.c_double * n)).contents
def arr(values):
    a = empty(len(values))
    a[:] = values
    return a
def fn(name, res, *args):
    g = getattr(lib, name)
    g.restype, g.argtypes = res, list(args)
    return g
step = fn("pc_fivebar_step", i, v, v, v, i, v, v, f, f, f, v, v, v)
p, s, motors = arr(d["p"]), arr(d["s"]), arr(d["motors"])
out = []
for n_motors in (0, 2):
    z = arr(d["z"] + [0.6, -0.9][:n_motors])
    volts = arr([3.0, -5.0][:n_motors]) if n_motors else None
    scratch = arr([0.0] * d["scratch"])
    for k in range(3):
        report, refusal = empty(d["report"]), empty(2)
        status = step(p, s, motors if n_motors else None, n_motors, z, volts, 0.01 * (k + 1), -0.02, 1e-3,
                      scratch, report, refusal)
        out += [status, *scratch[:len(z)], *report]
        z = arr(scratch[:len(z)])
dydt, res, rep, inv = empty(14), empty(6), empty(d["report"]), empty(d["inverse"])
z14, y = arr(d["z"]), arr(d["z"])
fn("pc_fivebar_derivative", None, v, v, f, f, f, v)(p, z14, 0.02, -0.03, 50.0, dydt)
fn("pc_fivebar_residual", None, v, v, v)(p, z14, res)
fn("pc_fivebar_report_of", None, v, v, v, v)(p, s, z14, rep)
fn("pc_fivebar_project", None, v, v, i)(p, y, 3)
fn("pc_fivebar_inverse_terms", None, v, v, v, v)(p, arr(d["z"][:7]), arr(d["z"][7:]), inv)
out += [*dydt, *res, *rep, *y, *inv]
print(" ".join(repr(float(x)) for x in out))
"""


def _blocks(stderr: str) -> list:
    """memcheck's reports, one string each (the lines of one process id between blank ones)."""
    return [b for b in re.split(r"\n==\d+== \n", stderr) if re.search(r"^==\d+== (Invalid|Conditional|Use of|Syscall)",
                                                                      b, re.M)]


def test_the_plants_kernel_calls_touch_no_word_they_do_not_own(tmp_path):
    """Catches a loop bound one past a buffer (a read of z[n], a write past the report), a
    kernel reading a local it never wrote (a loop over the chains that starts at the second
    and leaves the first's words of the step's trigonometry unset) and an output left partly
    unwritten, in the library in use: results alone need not change for any of them."""
    sim = PlantSimulator(get_preset("bench"), 0.02, 0.16, IntegratorSettings())
    p = sim._fast.p
    z = fast5r.project(p, np.concatenate([sim.y[:7], [0.05, -0.04, 0.0, 0.0, 0.0, 0.0, 0.0]]), 3)
    data = tmp_path / "inputs.json"
    data.write_text(json.dumps({"p": p.tolist(), "s": fast5r.pack_settings(0.0, 2, 1e-4, 1e-3, 1e-6, (2e-3, -3e-3)).tolist(),
                                "motors": sum(MOTORS, []), "z": z.tolist(), "scratch": fast5r.SCRATCH_WORDS,
                                "report": fast5r.REPORT_SIZE, "inverse": fast5r.INVERSE_SIZE}))
    library = Path(kernels.library()._name)
    child = tmp_path / "child.py"
    child.write_text(CHILD)
    run = subprocess.run([VALGRIND, "--tool=memcheck", "--track-origins=yes", "--leak-check=no",
                          sys.executable, str(child), str(library), str(data)],
                         env={**os.environ, "PYTHONMALLOC": "malloc"}, capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    values = [float(x) for x in run.stdout.split()]
    assert len(values) > 200 and np.isfinite(values).all()
    ours = [b for b in _blocks(run.stderr) if library.name in b]
    assert not ours, "\n\n".join(ours)[:6000]
