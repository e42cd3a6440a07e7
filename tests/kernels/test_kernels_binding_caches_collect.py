"""The caches of bound kernel calls kept outside their owners (kernels.owned's, controller/law.py's
binding, controller/trajectories.py's samplers): each registers its owner's finalizer before it
binds, so a binding that fails (a strided buffer: no address a kernel may take) leaves a finalizer
with no entry behind.  Collecting that owner must be silent and leave no entry: the finalizer's
``pop`` has its default."""
from __future__ import annotations

import gc
import math
import sys

import numpy as np
import pytest

import kernels
from controller import law
from controller import trajectories as tr
from controller.trajectories import CircleTrajectory


class Owner:
    """A controller's stand-in: any object a finalizer can be tied to."""


@pytest.fixture
def unraisable(monkeypatch):
    """The exceptions raised where nobody can catch them (a finalizer's), collected."""
    caught = []
    monkeypatch.setattr(sys, "unraisablehook", lambda record: caught.append(record.exc_value))
    return caught


def strided(n):
    return np.zeros(2 * n)[::2]


def _collect_silently(owner_ref, cache, key, unraisable):
    del owner_ref[:]
    gc.collect()
    assert unraisable == [] and key not in cache


def test_an_owner_whose_binding_failed_is_collected_silently(unraisable):
    """Catches kernels.owned's finalizer popping without a default (a KeyError at collection)."""
    owner = [Owner()]
    key = id(owner[0])
    with pytest.raises(ValueError, match="a kernel buffer must be C-contiguous"):
        kernels.owned(owner[0], (strided(4),), lambda buf: kernels.address(buf))
    _collect_silently(owner, kernels._OWNED, key, unraisable)


def test_a_controller_whose_law_binding_failed_is_collected_silently(unraisable):
    """Catches controller/law.py's binding finalizer popping without a default."""
    owner = [Owner()]
    key = id(owner[0])
    with pytest.raises(ValueError, match="a kernel buffer must be C-contiguous"):
        law.binding(owner[0], strided(8), np.zeros(8), np.zeros(8), None)
    _collect_silently(owner, law._BINDINGS, key, unraisable)


def test_a_trajectory_whose_sampler_failed_is_collected_silently(unraisable):
    """Catches controller/trajectories.py's sampler finalizer popping without a default: the
    values array a caller gives sample_values is strided, the binding refuses it."""
    owner = [CircleTrajectory(center=(0.0, 0.15), radius=0.05, initial_angle=0.0, angular_velocity=math.pi,
                              duration=2.0, stops=True, start_point=(0.05, 0.15))]
    key = id(owner[0])
    with pytest.raises(ValueError, match="a kernel buffer must be C-contiguous"):
        tr.sample_values(owner[0], 0.5, strided(len(tr.ReferenceSample._fields)), kernels.Refusal())
    _collect_silently(owner, tr._SAMPLERS, key, unraisable)
