"""scenarios/reference.py's drive checks (``_links``) at their edges, hit exactly, without an
integration: the scene's drives given made-up instances (issue 31, session 44: boundaries of
the generalised training sample)."""
from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import pytest

from scenarios import reference
from scenarios.scenes.catalogue import get_scene

#: A step at which 1e-12 of it is a whole number (5000) of its last place: T = h (1 +- 1e-12) exact.
H = 5e15 * 2.0 ** -62


def _instances(T=H, L=1e-3, v=(1.5, -2.5)):
    return {name: SimpleNamespace(slave=SimpleNamespace(drive=SimpleNamespace(T=T, params=SimpleNamespace(L=L), v=volts)))
            for name, volts in zip(("drive1", "drive2"), v)}


def _links(instances, order=("drive1", "drive2", "plant"), coupling="monolithic", step=H):
    system = dataclasses.replace(get_scene("bench_circle_PDq").system, step=step)
    return reference._links(system, instances, list(order), "plant", coupling)


def test_a_drive_period_exactly_1e_12_relative_off_the_step_is_the_step_and_one_float_farther_is_refused():
    """"their period is the step" up to 1e-12 relative, inclusive: both exact boundary periods
    link (each drive to its joint, with its voltage); one float farther is refused naming the
    drive and both values.  Catches ``>=`` for ``>``."""
    assert 1e-12 * H == 5000 * math.ulp(H)
    for T in (H + 1e-12 * H, H - 1e-12 * H):
        assert abs(T - H) == 1e-12 * H
        links = _links(_instances(T=T))
        assert {n: (k.joint, k.v) for n, k in links.items()} == {"drive1": (0, 1.5), "drive2": (1, -2.5)}
    for T in (math.nextafter(H + 1e-12 * H, 1.0), math.nextafter(H - 1e-12 * H, 0.0)):
        with pytest.raises(reference.ReferenceError) as refused:
            _links(_instances(T=T))
        assert str(refused.value) == f"drive drive1: controller period T = {T} s differs from the step {H} s"


def test_the_smallest_positive_inductance_has_an_electrical_state_and_zero_has_none():
    """L > 0 is an electrical state however small (5e-324 links); L = 0 and -0.0 are refused
    naming the drive.  Catches ``<`` for ``<=``."""
    assert set(_links(_instances(L=5e-324))) == {"drive1", "drive2"}
    for L in (0.0, -0.0):
        with pytest.raises(reference.ReferenceError, match=r"^drive drive1: L = 0 has no electrical state"):
            _links(_instances(L=L))


def test_a_drive_stepping_after_the_plant_is_refused_but_in_cosim_coupling():
    """Monolithic (and the other integrating couplings): a drive ordered after the plant has no
    voltage yet -- refused naming it; ``cosim`` takes its voltage from the previous step."""
    order = ("drive1", "plant", "drive2")
    with pytest.raises(reference.ReferenceError, match=r"^drive drive2 steps after the plant"):
        _links(_instances(), order=order)
    assert set(_links(_instances(), order=order, coupling="cosim")) == {"drive1", "drive2"}
    assert set(_links(_instances(), order=("plant", "drive1", "drive2"), coupling="cosim")) == {"drive1", "drive2"}
