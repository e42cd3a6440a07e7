"""``parcosim run SCENE --mode fmu --native`` (issue 28, item 3): a scene whose natively
built models run as native FMUs gives the run of the pythonfmu FMUs, every recorded signal
within 1e-12 of its peak (measured: bit for bit).  Wrong code it catches: a native FMU that
drifts from its twin over a closed loop, parameters not baked into the native FMU, a native
FMU not actually used (checked: the components' models are native files)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim.master import simulate
from fmus.native.models import NATIVE
from fmus.native.run import native_system
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant

pytestmark = [pytest.mark.fmu]


#: Per scene, the components that run native (the others: pythonfmu FMUs).
NATIVE_COMPONENTS = {"bench_circle_TCMDx": {"traj", "deriv", "ctrl", "obs1", "obs2", "drive1", "drive2", "plant"},
                     "bench_real_circle_TCMDx": {"traj", "deriv", "ctrl", "obs1", "obs2", "drive1", "drive2", "plant"},
                     "pendulum_push": {"ctrl", "drive_l", "drive_r", "plant"},
                     # the drives inside the plant: an ActuatedFiveBarPlant (parcosim run --drives-in-plant 1)
                     "bench_circle_TCMDx --drives-in-plant": {"traj", "deriv", "ctrl", "obs1", "obs2", "plant"}}


def system_of(key: str):
    """1.5 s of the system of a scene name, or of "SCENE --drives-in-plant" (its drives inside
    the plant, as ``parcosim run --drives-in-plant 1`` makes it)."""
    name, _, variant = key.partition(" ")
    scene = drives_in_plant(get_scene(name), substeps=1) if variant == "--drives-in-plant" else get_scene(name)
    return replace(scene.system, stop_time=1.5)


@pytest.mark.parametrize("scene", sorted(NATIVE_COMPONENTS))
def test_scene_with_native_fmus_equals_the_pythonfmu_run(scene, built_fmus, tmp_path):
    """Native: the bench's Trajectory, Derivator, current observers, drives (the bench twin's:
    LuGre friction, PWM, current noise and offset), PositionController (TCMDx on
    the tabulated model) and FiveBarPlant (the bench preset, started
    at rest at (x0, y0)); the pendulum's plant, balance controller and drives (with a push at 1 s);
    the bench with its drives inside an ActuatedFiveBarPlant."""
    system = system_of(scene)
    fmu_dir = next(iter(built_fmus.values())).parent
    native = native_system(system, tmp_path / "native")
    swapped = [c for c in native.components if c.model.endswith(".fmu")]
    assert {c.name for c in swapped} == NATIVE_COMPONENTS[scene]
    assert NATIVE_COMPONENTS[scene] == {c.name for c in system.components if c.model in NATIVE}
    a = simulate(system, mode="fmu", fmu_dir=fmu_dir)
    b = simulate(native, mode="fmu", fmu_dir=fmu_dir)
    assert a.error is None and b.error is None
    assert np.array_equal(a.time, b.time)
    for name, values in a.signals.items():
        peak = np.max(np.abs(values))
        assert np.max(np.abs(np.asarray(b.signals[name]) - values)) <= 1e-12 * peak, name
