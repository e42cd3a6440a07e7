"""The 5R's closed-form kinematics (kernels/src/kinematics5r.c) on the boundaries of what they
accept: lengths that are powers of two, so that a stretched or folded chain and two touching
circles are exact in floating point.  On the boundary the mechanism assembles (one point, the
chain's angles equal or opposite); a little past it, it is refused with the distance."""
from __future__ import annotations

import ctypes
import math

import pytest

import kernels
from plant import kinematics5r as k5r

NUDGE = 2.0 ** -30
_D = ctypes.POINTER(ctypes.c_double)
#: One chain's inverse kinematics (kinematics5r.h), which pc_5r_inverse calls for each chain.
chain_ik = kernels.function("pc_5r_chain_ik", ctypes.c_int, *[ctypes.c_double] * 5, _D, _D, _D)


def _forward(g, q1, q2):
    x, y, distance = ctypes.c_double(), ctypes.c_double(), ctypes.c_double(float("nan"))
    code = k5r.forward(ctypes.byref(g), q1, q2, ctypes.byref(x), ctypes.byref(y), ctypes.byref(distance))
    return code, x.value, y.value, distance.value


# l0 = l11 = l21 = 1/4, q1 = q2 = 0: the elbows at (1/2, 0) and (0, 0), 1/2 apart.  `past`: the
# distal lengths nudged so that the circles no longer meet.
@pytest.mark.parametrize("l12, l22, tip, past", [
    (0.25, 0.25, 0.25, [(0.25 - NUDGE, 0.25), (0.25, 0.25 - NUDGE)]),    # touch outside: l12 + l22 = 1/2
    (0.75, 0.25, -0.25, [(0.75 + NUDGE, 0.25), (0.75, 0.25 - NUDGE)]),   # inside: l12 - l22 = 1/2
    (0.25, 0.75, 0.75, [(0.25 - NUDGE, 0.75), (0.25, 0.75 + NUDGE)]),    # inside: l22 - l12 = 1/2
])
def test_distal_circles_that_touch_assemble_at_the_touching_point(l12, l22, tip, past):
    """Catches a forward kinematics that refuses elbows exactly l12 + l22 or |l12 - l22| apart
    (``>=`` / ``<=`` for ``>`` / ``<``), or puts the single tip elsewhere; nudged past either
    boundary, refused with the elbows' distance."""
    code, x, y, _ = _forward(k5r.Geometry(0.25, 0.25, l12, 0.25, l22), 0.0, 0.0)
    assert (code, x, y) == (k5r.OK, tip, 0.0)
    assert abs(x - 0.5) == l12 and abs(x) == l22                  # on both circles
    for n12, n22 in past:
        code, _, _, distance = _forward(k5r.Geometry(0.25, 0.25, n12, 0.25, n22), 0.0, 0.0)
        assert (code, distance) == (k5r.NO_ASSEMBLY, 0.5), (n12, n22)


@pytest.mark.parametrize("py", [0.0, -0.0])
@pytest.mark.parametrize("elbow", [1.0, -1.0])
@pytest.mark.parametrize("px, stretched", [(0.375, True), (0.125, False)])
def test_a_chain_reaches_a_point_exactly_stretched_or_folded(px, stretched, elbow, py):
    """Catches an inverse kinematics that refuses cos(beta) = +1 or -1 (a chain of 1/4 and
    1/8 m reaching a point 3/8 or 1/8 m from its base): the angles are the point's direction
    and the distal link along it (stretched) or back (folded); a point nudged further out
    (or in) is refused with its distance.  Either elbow: phi1 = atan2(py, px) - atan2(b, a) = 0
    exactly (b = -0 for elbow -1: no full turn added to an angle of 0), phi2 = elbow * beta.  A point
    at y = -0.0 gives phi1 = -0.0, still no full turn (seed 4101 [283]: ``p1 >= 0.0`` took one off)."""
    phi1, phi2 = ctypes.c_double(), ctypes.c_double()
    code = chain_ik(0.25, 0.125, px, py, elbow, ctypes.byref(phi1), ctypes.byref(phi2), None)
    assert code == k5r.OK and phi1.value == 0.0
    assert phi2.value == pytest.approx(0.0 if stretched else elbow * 3.141592653589793, abs=1e-7)
    beyond = px + NUDGE if stretched else px - NUDGE
    distance = ctypes.c_double()
    assert chain_ik(0.25, 0.125, beyond, py, elbow, ctypes.byref(phi1), ctypes.byref(phi2),
                        ctypes.byref(distance)) == k5r.OUT_OF_REACH
    assert distance.value == beyond


def test_elbows_at_one_point_are_no_assembly_with_distance_zero():
    """Both bases at the origin (l0 = 0), equal proximal links at one angle: the elbows coincide,
    and with equal distal links every point of one circle is a tip; refused (NO_ASSEMBLY, the
    elbows' distance 0), not a tip computed through 1 / 0.  Catches the coincidence test
    dropped (the reach tests alone pass a distance of 0 between equal circles)."""
    code, x, y, distance = _forward(k5r.Geometry(0.0, 0.25, 0.25, 0.25, 0.25), 0.3, 0.3)
    assert (code, distance) == (k5r.NO_ASSEMBLY, 0.0)
    code, x, y, distance = _forward(k5r.Geometry(0.0, 0.25, 0.25, 0.25, 0.25), 0.3, 0.3 + NUDGE)
    # the elbows 2^-32 m apart: two circles that cross, a finite tip 1/4 m from the first elbow
    assert code == k5r.OK and math.hypot(x - 0.25 * math.cos(0.3), y - 0.25 * math.sin(0.3)) == pytest.approx(0.25)
