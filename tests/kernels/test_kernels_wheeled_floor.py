"""Where the wheeled pendulum's body meets the floor (kernels/src/wheeled.c): the lowest point of
a box of depth D and height H standing on the axle (at height R), tilted by psi, against the
four corners of that box turned by psi here; and the fall it makes the kernel refuse."""
from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest

import kernels
from plant import wheeled_kernel as K
from plant.wheeled import SEED, pack

lowest_body_point = kernels.function("pc_wheeled_lowest_body_point", ctypes.c_double, ctypes.c_void_p,
                                     ctypes.c_double)


def corners_lowest(R, D, H, psi):
    """The lowest of the box's corners (u across the body, v up it from the axle) turned by psi."""
    return R + min(v * math.cos(psi) + u * math.sin(psi) for u in (-D / 2, D / 2) for v in (0.0, H))


@pytest.mark.parametrize("changes", [{}, dict(D=0.2), dict(H=0.05, D=0.3, R=0.02), dict(H=0.0)])
def test_the_lowest_body_point_is_the_lowest_corner_at_every_tilt(changes):
    """Catches a wrong term of the lowest point: the box's top corners below the axle once it
    is tilted past 90 degrees (min(0, H cos psi)), the half depth, |sin psi|, the axle height."""
    p = SEED.with_(**changes)
    prm = pack(p)
    for psi in np.linspace(-math.pi, math.pi, 73):
        assert lowest_body_point(kernels.address(prm), psi) == pytest.approx(
            corners_lowest(p.R, p.D, p.H, psi), abs=1e-15)


@pytest.mark.parametrize("D", [0.1, 0.2])
def test_the_kernel_calls_it_a_fall_exactly_when_a_corner_reaches_the_floor(D):
    """Catches a floor check with a margin, on the wrong side, or naming another state: at tilts
    either side of where a bottom corner touches (R = D/2 |sin psi|), the condition is OK above
    the floor and FALLEN_FLOOR (naming psi) on or below it."""
    p = SEED.with_(D=D)
    prm, y = pack(p), np.zeros(K.N_STATE)
    touch = math.asin(p.R / (D / 2))
    for psi in (-touch - 1e-6, -touch + 1e-6, touch - 1e-6, touch + 1e-6, 0.5 * touch):
        y[K.PSI] = psi
        refusal = kernels.Refusal()
        code = K.condition(prm, y, refusal)
        if corners_lowest(p.R, D, p.H, psi) > 0.0:
            assert code == K.OK, psi
        else:
            assert (code, refusal.value) == (K.FALLEN_FLOOR, psi)


def test_a_fall_to_the_floor_is_refused_word_for_word_with_its_unit():
    """The kernel's FALLEN_FLOOR at a tilt below the touching one, through plant.wheeled's
    refusal_error: a FallenError naming psi in rad, the reason fallen_floor, and the message
    written here (the fall, the time, the pitch in degrees at the last good state).  Catches
    the reason's unit and text exchanged, or another fall's words."""
    from plant.wheeled import FallenError, refusal_error

    p = SEED.with_(D=0.2)
    prm, y = pack(p), np.zeros(K.N_STATE)
    y[K.PSI] = math.asin(p.R / (p.D / 2)) + 1e-6
    refusal = kernels.Refusal()
    assert K.condition(prm, y, refusal) == K.FALLEN_FLOOR
    error = refusal_error(refusal, 0.125, 0.5)
    assert isinstance(error, FallenError)
    record = error.record()
    assert (record["variable"], record["unit"], record["reason"], record["time"]) == ("psi", "rad", "fallen_floor",
                                                                                        0.125)
    assert str(error) == ("the robot fell over (body touching the floor) at t = 0.125 s: psi = "
                          f"{math.degrees(0.5):.4g} deg at the last good state")
