"""The vertical bench scenes (``vertical_circle_<S>``, ``vertical_circle_balanced_<S>``):
gravity and counter-masses reach the plant and the controller's model, and the balanced
package runs in fmpy as in our master."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from scenarios.run.runner import run_scene
from scenarios.scenes.catalogue import get_scene, scene_names
from scenarios.scenes.thesis import VERTICAL_COUNTER_MASSES, VERTICAL_GRAVITY, Fidelity, vertical_circle
from scenarios.studies.tools import compare, short


def test_names_and_what_reaches_plant_and_controller():
    """Catches a vertical scene whose gravity or counter-masses differ between plant and controller."""
    names = scene_names()
    for s in ("TCMDx", "PDq", "SMCx"):
        assert f"vertical_circle_{s}" in names and f"vertical_circle_balanced_{s}" in names
    for balanced in (False, True):
        system = get_scene(f"vertical_circle_{'balanced_' if balanced else ''}TCx").system
        plant, ctrl = system.component("plant").parameters, system.component("ctrl").parameters
        assert (plant["gravity_x"], plant["gravity_y"]) == (ctrl["gravity_x"], ctrl["gravity_y"]) \
            == VERTICAL_GRAVITY[:2]
        expected = VERTICAL_COUNTER_MASSES if balanced else (0.0, 0.0)
        for j, value in zip(("1", "2"), expected):
            assert plant.get(f"counter_mass{j}", 0.0) == ctrl.get(f"counter_mass{j}", 0.0) == value


def _e_ef(scene, stop=2.0):
    scene = dataclasses.replace(scene, system=dataclasses.replace(scene.system, stop_time=stop),
                                window=(1.0, stop))
    outcome = run_scene(scene)
    assert outcome.result.error is None
    return outcome.metrics


@pytest.mark.parametrize("balanced", [False, True])
def test_the_controller_model_knows_gravity_and_counter_masses(balanced):
    """TCx over [1, 2] s: the scene's controller (model with the plant's gravity and
    counter-masses) tracks at least 3x better than the same controller whose model lacks
    them (gravity unknown, or counter-masses unknown)."""
    good = _e_ef(vertical_circle("TCx", balanced))["e_ef_mm"]
    counter = VERTICAL_COUNTER_MASSES if balanced else (0.0, 0.0)
    blind = vertical_circle("TCx", balanced, fidelity=Fidelity())
    ctrl = blind.system.component("ctrl")
    params = {k: v for k, v in ctrl.parameters.items() if not k.startswith(("gravity", "counter"))}
    if balanced:     # the model knows gravity but not the counter-masses
        params.update(gravity_x=VERTICAL_GRAVITY[0], gravity_y=VERTICAL_GRAVITY[1])
    components = tuple(dataclasses.replace(c, parameters=params) if c.name == "ctrl" else c
                       for c in blind.system.components)
    blind = dataclasses.replace(blind, system=dataclasses.replace(blind.system, components=components))
    assert counter == tuple(blind.system.component("plant").parameters.get(f"counter_mass{j}", 0.0)
                            for j in "12")
    assert _e_ef(blind)["e_ef_mm"] > 3.0 * good


def test_balanced_package_tracks_in_fmpy_as_in_our_master(tmp_path):
    """`parcosim export-ssp vertical_circle_balanced_TCMDx`: the counter-masses and gravity
    are baked into both FMUs of the package; fmpy's simulate_ssp tracks as our master
    (e_ef and tau_ef over [1, 2] s within 5 %)."""
    scene = dataclasses.replace(short(get_scene("vertical_circle_balanced_TCMDx"), 2.0), window=(1.0, 2.0))
    (tool, m, ours, error), = compare(scene, ("fmpy",), isolated=False, out_dir=tmp_path)
    assert error is None and m["completed"], error
    assert 0.95 <= m["e_ef_mm"] / ours["e_ef_mm"] <= 1.05, (m["e_ef_mm"], ours["e_ef_mm"])
    assert 0.95 <= m["tau_ef_Nm"] / ours["tau_ef_Nm"] <= 1.05, (m["tau_ef_Nm"], ours["tau_ef_Nm"])
    assert np.isfinite(ours["e_ef_mm"])
