"""pc_5r_clear (kernels/src/kinematics5r.c), the task-space law's cheap check of a reference, at
its elbow threshold: kinematics5r.h says it answers 0 for "an elbow within 1e-3 of stretched or
folded" (|sin beta| below 1e-3, where the distal direction is too ill-conditioned to bound),
whatever the band; just above it, with a band far below every margin, 1 (session 44, training
4411 generalised: a constant no test looked at)."""
from __future__ import annotations

import ctypes
import math

import pytest

import kernels
from plant import get_preset
from plant import kinematics5r as k5r

clear = kernels.function("pc_5r_clear", ctypes.c_int, ctypes.POINTER(k5r.Geometry), ctypes.c_double,
                         ctypes.c_double, ctypes.c_double)


def _point_with_elbow_sine(g, s):
    """A point that chain 1 (base (l0, 0)) reaches with |sin beta1| = s, nearly folded, up and to
    the right of its base, where chain 2 is far from its own singularities."""
    cos_b = -math.sqrt(1.0 - s * s)
    r = math.sqrt(g.l11 ** 2 + g.l12 ** 2 + 2.0 * g.l11 * g.l12 * cos_b)
    a = math.radians(60.0)
    return g.l0 + r * math.cos(a), r * math.sin(a)


@pytest.mark.parametrize("s", [5e-4, 9e-4, 0.995e-3, 1.005e-3, 1.2e-3, 1.9e-3, 3e-3])
def test_an_elbow_within_one_thousandth_of_folded_is_never_clear(s):
    """With the band at -1 (below any margin), pc_5r_clear is 1 exactly when both elbows' |sin|
    are at least 1e-3: here chain 1's, set to s (its value recomputed from the point), chain 2's
    well clear."""
    g = k5r.geometry(get_preset("bench"))
    x, y = _point_with_elbow_sine(g, s)
    angles, distance = (ctypes.c_double * 4)(), ctypes.c_double()
    assert k5r.inverse(g, x, y, angles, distance) == k5r.OK
    serial1 = abs(math.sin(angles[1] - angles[0]))
    serial2 = abs(math.sin(angles[3] - angles[2]))
    assert serial1 == pytest.approx(s, rel=1e-3) and serial2 > 0.05
    assert clear(g, x, y, -1.0) == (1 if s > 1e-3 else 0)
