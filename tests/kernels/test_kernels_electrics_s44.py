"""The armature circuit's coefficient kernels (kernels/src/electrics.c) called directly, as the
native FMUs call them (docs/native.md): electrics.h's codes, which motor/electrics.py's own
checks make unreachable from Python — BAD_METHOD (1) for an unknown method or for Euler with
L = 0, the output left alone; 0 and the documented (a, g), (w_i, w_u) otherwise (session 44,
training 4411 generalised: a refusal branch no test took)."""
from __future__ import annotations

import ctypes
import math

import pytest

import kernels

EXACT, EULER, QUASI_STATIC, BAD_METHOD = 0, 1, 2, 1
_ARGS = (ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_int, ctypes.POINTER(ctypes.c_double))
STEP = kernels.function("pc_electrical_step_coefficients", ctypes.c_int, *_ARGS)
MEAN = kernels.function("pc_mean_current_coefficients", ctypes.c_int, *_ARGS)
R, L, H = 1.25, 0.5e-3, 1e-3


def _call(kernel, R, L, h, method):
    out = (ctypes.c_double * 2)(-7.5, -7.5)
    return kernel(R, L, h, method, out), (out[0], out[1])


@pytest.mark.parametrize("kernel", [STEP, MEAN], ids=["step", "mean"])
@pytest.mark.parametrize("method, L_", [(EULER, 0.0), (3, L), (-1, L), (3, 0.0)])
def test_an_unknown_method_or_euler_without_inductance_is_bad_method_and_writes_nothing(kernel, method, L_):
    """electrics.h: BAD_METHOD for an unknown method or Euler with L = 0 (its a and g would divide
    by L); the mean's kernel passes the step's code on; nothing written."""
    assert _call(kernel, R, L_, H, method) == (BAD_METHOD, (-7.5, -7.5))


def test_each_method_gives_its_documented_coefficients():
    """electrics.h: exact a = exp(-R h / L), g = (1 - a) / R; Euler a = 1 - h R / L, g = h / L;
    quasi-static, and exact with L = 0, a = 0, g = 1 / R; the means: exact w_i = (1 - a) / x,
    w_u = (1 - w_i) / R (x = R h / L), Euler (1 + a) / 2 and g / 2, quasi-static (0, 1 / R)."""
    x = R * H / L
    a = math.exp(-x)
    code, (a_, g_) = _call(STEP, R, L, H, EXACT)
    assert code == 0 and a_ == pytest.approx(a, rel=1e-15) and g_ == pytest.approx((1 - a) / R, rel=1e-15)
    assert _call(STEP, R, L, H, EULER) == (0, (1.0 - H * R / L, H / L))
    assert _call(STEP, R, L, H, QUASI_STATIC) == (0, (0.0, 1.0 / R))
    assert _call(STEP, R, 0.0, H, EXACT) == (0, (0.0, 1.0 / R))
    code, (w_i, w_u) = _call(MEAN, R, L, H, EXACT)
    assert code == 0 and w_i == pytest.approx((1 - a) / x, rel=1e-15)
    assert w_u == pytest.approx((1 - w_i) / R, rel=1e-15)
    assert _call(MEAN, R, L, H, EULER) == (0, (0.5 * (1.0 + (1.0 - H * R / L)), 0.5 * (H / L)))
    assert _call(MEAN, R, L, H, QUASI_STATIC) == (0, (0.0, 1.0 / R))
    assert _call(MEAN, R, 0.0, H, EXACT) == (0, (0.0, 1.0 / R))
