"""The kernels' inline sin and cos (kernels/src/pc_trig.h) against libm and against the true
values (mpmath at 300 bits): within 1 ulp of libm and 1.5 ulp of the truth over its fast range
(|x| <= 1e3 rad), exact where the answer is exact, libm's own answer outside that range (and
for NaN, inf).

A small C program built here with the kernels' flags calls ``pc_sincos`` on an array of
angles (the header's functions are inline: the library exports none of them).
"""
from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest

from kernels import build

HARNESS = r"""
#include <stdio.h>
#include <math.h>
#include "pc_trig.h"
int main(int argc, char **argv)
{
    if (argc != 3) return 2;
    FILE *in = fopen(argv[1], "rb"), *out = fopen(argv[2], "wb");
    double x;
    if (!in || !out) return 2;
    while (fread(&x, sizeof x, 1, in) == 1) {
        double sc[2];
        pc_sincos(x, &sc[0], &sc[1]);
        if (pc_sin(x) != sc[0] && !(isnan(sc[0]) && isnan(pc_sin(x)))) return 3;
        fwrite(sc, sizeof sc, 1, out);
    }
    return fclose(in) || fclose(out);
}
"""


@pytest.fixture(scope="module")
def sincos(tmp_path_factory):
    """(sin x, cos x) of the array x by pc_sincos."""
    folder = tmp_path_factory.mktemp("trig")
    program = folder / "sincos"
    (folder / "sincos.c").write_text(HARNESS)
    flags = [f for f in build.FLAGS if f not in ("-shared", "-fPIC")]
    subprocess.run([build.compiler(), *flags, f"-I{build.SOURCES}", str(folder / "sincos.c"), "-o", str(program),
                    "-lm"], check=True)

    def call(x):
        x = np.ascontiguousarray(x, dtype=np.float64)
        x.tofile(folder / "x.bin")
        subprocess.run([str(program), str(folder / "x.bin"), str(folder / "sc.bin")], check=True)
        sc = np.fromfile(folder / "sc.bin", dtype=np.float64).reshape(-1, 2)
        return sc[:, 0], sc[:, 1]
    return call


def ulps(a, b) -> np.ndarray:
    """Distance in units in the last place between the doubles a and b (same sign or zero)."""
    def ordered(v):
        i = np.asarray(v, dtype=np.float64).view(np.int64)
        return np.where(i < 0, np.int64(-2 ** 63) - i, i)
    return np.abs(ordered(a) - ordered(b))


def angles(rng) -> np.ndarray:
    """Uniform over the 5R's angles, over +-100 rad and over the fast range +-1e3, and the
    quadrant edges there: k pi/4 and their neighbours."""
    edges = np.arange(-1273, 1274) * (math.pi / 4)
    return np.concatenate([rng.uniform(-2 * math.pi, 2 * math.pi, 150_000), rng.uniform(-100, 100, 50_000),
                           rng.uniform(-1e3, 1e3, 100_000), edges, np.nextafter(edges, math.inf),
                           np.nextafter(edges, -math.inf)])


def test_within_one_ulp_of_libm_over_the_range(sincos):
    """Catches an inline sin or cos more than 1 ulp from libm in the fast range."""
    x = angles(np.random.default_rng(27))
    s, c = sincos(x)
    libm_s = np.array([math.sin(v) for v in x])   # math.sin is the C library's
    libm_c = np.array([math.cos(v) for v in x])
    assert ulps(s, libm_s).max() <= 1 and ulps(c, libm_c).max() <= 1
    assert np.mean(s == libm_s) > 0.6                     # mostly the same double


def test_within_one_and_a_half_ulp_of_the_true_values(sincos):
    """Catches an inline sin or cos more than 1.5 ulp from the true value (mpmath)."""
    import mpmath

    rng = np.random.default_rng(2712)
    x = np.concatenate([rng.uniform(-2 * math.pi, 2 * math.pi, 1500), rng.uniform(-1e3, 1e3, 500),
                        np.arange(1, 200) * (math.pi / 2)])
    s, c = sincos(x)
    with mpmath.workprec(300):
        true_s = [mpmath.sin(mpmath.mpf(v)) for v in x]
        true_c = [mpmath.cos(mpmath.mpf(v)) for v in x]
    for got, true in ((s, true_s), (c, true_c)):
        err = [abs(mpmath.mpf(g) - t) / mpmath.mpf(math.ulp(float(t))) for g, t in zip(got, true)]
        assert max(err) <= 1.5, max(err)


def test_exact_values_and_signs(sincos):
    """Catches an inline sin or cos that loses -0.0, a subnormal or a tiny angle."""
    x = np.array([0.0, -0.0, 1e-300, -1e-300, 5e-324, 1e-9])
    s, c = sincos(x)
    assert s.tolist() == [0.0, -0.0, 1e-300, -1e-300, 5e-324, 1e-9]
    assert np.signbit(s).tolist() == [False, True, False, True, False, False]
    assert c.tolist() == [1.0] * 6


def test_outside_the_fast_range_it_is_libm(sincos):
    """Catches an inline sin or cos that does not hand large or non-finite angles to libm."""
    x = np.array([1e3 + 1e-9, -1234.5, 1e5, -3e7, 1e300, math.inf, -math.inf, math.nan])
    s, c = sincos(x)
    for v, sv, cv in zip(x, s, c):
        if math.isfinite(v):
            assert (sv, cv) == (math.sin(v), math.cos(v))
        else:
            assert math.isnan(sv) and math.isnan(cv)


def test_a_wrong_reduction_would_show(sincos):
    """sin(x + pi) = -sin(x) and cos(x - pi/2) = sin(x) to the rounding of the shifted angle:
    a quadrant or a sign wrong by one shows here as an error of order one."""
    x = np.random.default_rng(7).uniform(-50, 50, 20_000)
    s, c = sincos(x)
    s_pi, _ = sincos(x + math.pi)
    _, c_half = sincos(x - math.pi / 2)
    assert np.max(np.abs(s_pi + s)) < 1e-13 and np.max(np.abs(c_half - s)) < 1e-13
