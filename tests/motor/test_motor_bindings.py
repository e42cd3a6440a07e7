"""The ctypes signatures of the motor's kernel bindings (``motor/kernel.py``, the electrics'
coefficient kernels of ``motor/electrics.py``) against the C prototypes in
``kernels/src/*.h``: as many arguments, each of the declared kind.

A binding missing its last pointer argument still runs on the x86-64 System V ABI (ctypes
passes the extra array as a variadic pointer), but not where variadic arguments travel
differently (Apple arm64 puts them on the stack): the declaration must be the prototype's.
"""
import ctypes
import math
import re
from pathlib import Path

import pytest

import kernels
from motor import electrics
from motor import kernel as mk

SRC = Path(kernels.__file__).resolve().parent / "src"


def _prototypes():
    """{name: (return type, [parameter types])} of every ``pc_*`` function declared in a header."""
    out = {}
    for header in SRC.glob("*.h"):
        text = re.sub(r"/\*.*?\*/", " ", header.read_text(), flags=re.S)
        for m in re.finditer(r"^([A-Za-z_][\w \*]*?)\s*\b(pc_\w+)\s*\(([^)]*)\)\s*;", text, flags=re.M):
            params = [p.strip() for p in m[3].split(",") if p.strip() and p.strip() != "void"]
            out[m[2]] = (m[1].strip(), params)
    return out


def _kind(c_type: str):
    """A C declaration's kind ("double h", "double *ag", "double phi[2]", a return type):
    "ptr", "double", "int", "u64", "void"."""
    if "*" in c_type or "[" in c_type:
        return "ptr"
    words = c_type.replace("const ", "").split()
    return {"double": "double", "int": "int", "uint64_t": "u64", "void": "void"}[words[0]]


def _ctypes_kind(t):
    if t is None:
        return "void"
    if t is ctypes.c_void_p or (isinstance(t, type) and issubclass(t, ctypes._Pointer)):
        return "ptr"
    if t is ctypes.c_double:
        return "double"
    if t is ctypes.c_int:
        return "int"
    if t is ctypes.c_uint64:
        return "u64"
    raise AssertionError(f"unexpected ctypes type {t!r}")


def _bindings():
    found = {f.__name__: f for f in vars(mk).values() if isinstance(f, ctypes._CFuncPtr)}
    for name in ("pc_electrical_step_coefficients", "pc_mean_current_coefficients"):
        found[name] = electrics._coefficients_kernel(name)
    return found


def test_the_motor_binds_the_electrics_coefficient_kernels_and_its_own():
    names = set(_bindings())
    assert {"pc_electrical_step_coefficients", "pc_mean_current_coefficients", "pc_drive_torque",
            "pc_lugre_push", "pc_controller_update"} <= names


@pytest.mark.parametrize("name", sorted(_bindings()))
def test_each_binding_declares_the_c_prototypes_arguments_and_result(name):
    f, (ret, params) = _bindings()[name], _prototypes()[name]
    assert [_ctypes_kind(t) for t in f.argtypes] == [_kind(p) for p in params], (name, params)
    assert _ctypes_kind(f.restype) == _kind(ret)


def test_the_coefficient_kernels_write_both_coefficients_through_their_pointer():
    """(a, g) of the exact step, a = exp(-R h / L), and the mean current's (w_i, w_u)."""
    R, L, h = 1.1, 0.667e-3, 1e-4
    a, g = electrics.electrical_step_coefficients(R, L, h, "exact")
    x = R * h / L
    assert a == pytest.approx(math.exp(-x), rel=1e-14)
    w_i, w_u = electrics.mean_current_coefficients(R, L, h, "exact")
    assert w_i == pytest.approx((1.0 - math.exp(-x)) / x, rel=1e-12)
    assert w_u == pytest.approx((1.0 - w_i) / R, rel=1e-12)
