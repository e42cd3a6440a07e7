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


@pytest.mark.parametrize("scene", ["bench_circle_TCMDx", "pendulum_push"])
def test_scene_with_native_fmus_equals_the_pythonfmu_run(scene, built_fmus, tmp_path):
    """Native: the bench's Derivators and Trajectory; the pendulum's plant and balance
    controller (with a push at 1 s)."""
    system = replace(get_scene(scene).system, stop_time=1.5)
    fmu_dir = next(iter(built_fmus.values())).parent
    native = native_system(system, tmp_path / "native")
    swapped = [c for c in native.components if c.model.endswith(".fmu")]
    assert swapped and {c.name for c in swapped} == {c.name for c in system.components if c.model in NATIVE}
    a = simulate(system, mode="fmu", fmu_dir=fmu_dir)
    b = simulate(native, mode="fmu", fmu_dir=fmu_dir)
    assert a.error is None and b.error is None
    assert np.array_equal(a.time, b.time)
    for name, values in a.signals.items():
        peak = np.max(np.abs(values))
        assert np.max(np.abs(np.asarray(b.signals[name]) - values)) <= 1e-12 * peak, name
