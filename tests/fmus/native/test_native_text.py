"""The native FMUs write floats in messages as Python does (fmus/native/pcn_text.c): repr()
(shortest round trip), format(x, ".6g") and format(x, ".3g"), checked against Python itself on hand-picked
edge values, every power of two, random bit patterns and hypothesis' floats."""
from __future__ import annotations

import struct
import subprocess

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fmus.native.build import HERE

PROGRAM = r"""
#include <stdio.h>
#include "pcn_text.h"
int main(void)
{
    double x;
    while (fread(&x, sizeof x, 1, stdin) == 1) {
        pcn_text t;
        pcn_clear(&t);
        pcn_addf(&t, "%r|%G|%g", x, x, x);
        puts(t.text);
    }
    return 0;
}
"""
EDGES = [0.0, -0.0, 0.1, 0.2 + 0.1, 1.0, -1.5, 100.0, 1e16, 1e15, 9999999999999998.0, 1e-4, 1e-5, 1.5e-5,
         123456789.125, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, 1e22, 1e23, 0.001, 2.5e-10,
         float("nan"), float("inf"), float("-inf"), 1 / 3, 2.0 ** 53 + 2, 4.35, 0.3]


@pytest.fixture(scope="module")
def formatter(tmp_path_factory):
    folder = tmp_path_factory.mktemp("text")
    (folder / "main.c").write_text(PROGRAM)
    exe = folder / "format"
    subprocess.run(["cc", "-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-Wshadow", f"-I{HERE}",
                    str(folder / "main.c"), str(HERE / "pcn_text.c"), "-lm", "-o", str(exe)], check=True)

    def run(values):
        data = b"".join(struct.pack("=d", v) for v in values)
        lines = subprocess.run([str(exe)], input=data, capture_output=True, check=True).stdout.decode().splitlines()
        return [line.split("|") for line in lines]
    return run


def check(formatter, values):
    for value, (r, g, g3) in zip(values, formatter(values), strict=True):
        assert r == repr(float(value)), value
        assert g == format(float(value), ".6g"), value
        assert g3 == format(float(value), ".3g"), value


def test_edges_and_every_power_of_two(formatter):
    """Catches a C float formatter that differs from Python's repr at an edge value or a power of two."""
    check(formatter, EDGES + [2.0 ** k for k in range(-1074, 1024)] + [-(2.0 ** k) * 3 for k in range(-1000, 1000)])


def test_random_bit_patterns(formatter):
    """Catches a C float formatter that differs from Python's repr on any of 50000 random doubles."""
    values = np.frombuffer(np.random.default_rng(28).bytes(8 * 50000), dtype=np.float64)
    check(formatter, [float(v) for v in values])


@settings(max_examples=300, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=1, max_size=50))
def test_hypothesis_floats(formatter, values):
    """Catches a C float formatter that differs from Python's repr on edge doubles (inf, nan, subnormal)."""
    check(formatter, values)
