"""The vertical scenes against what they claim (scenarios/scenes/thesis.py ``vertical_circle``:
"the bench standing in a vertical plane, tracking the circle (7.23)"; SYSTEM.md section 5's
circle window [1, 8] s, held 3 s more), and its ``frequency`` option against the circle sampled
here: 8 turns at f Hz, the window turns 2 to 8 (issue 31: the defaults and an option away from
them, against values written from the texts, not read from the builders)."""
from __future__ import annotations

import math
import re

import pytest

from controller.trajectories import from_parameters
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.thesis import vertical_circle


def _circle(t, f=1.0):        # (7.23): centre (0, 0.158), radius 0.05, from the start point (7.28)
    return -0.05 * math.sin(2 * math.pi * f * t), 0.158 - 0.05 * math.cos(2 * math.pi * f * t)


def _plain(parameters):
    return {k: v for k, v in parameters.items() if not k.startswith(("gravity", "model_gravity", "counter_"))}


@pytest.mark.parametrize("name", ["vertical_circle_PDMDq", "vertical_circle_balanced_TCx"])
def test_a_vertical_scene_is_the_bench_circle_at_1_hz_but_for_gravity_and_counter_masses(name):
    """Catches a vertical scene at another frequency (a changed default), window, stop time,
    start, strategy or wiring than the bench circle's of its strategy."""
    scene = get_scene(name)
    bench = get_scene("bench_circle_" + name.rsplit("_", 1)[1])
    assert (scene.window, scene.reference_end, scene.system.stop_time) == ((1.0, 8.0), 8.0, 11.0)
    assert scene.strategy == bench.strategy and scene.system.connections == bench.system.connections
    assert scene.system.step == bench.system.step
    for mine, theirs in zip(scene.system.components, bench.system.components):
        assert mine.name == theirs.name and mine.model == theirs.model
        assert _plain(mine.parameters) == _plain(theirs.parameters), mine.name
    reference = from_parameters(**scene.system.component("traj").parameters)
    for t in (0.0, 0.3, 4.55, 7.9):
        r = reference(t)
        assert (r.x, r.y) == pytest.approx(_circle(t), abs=1e-12)
    assert "circle (7.23) at 1 Hz" in scene.description


@pytest.mark.parametrize("frequency", [0.5, 2.0])
def test_another_frequency_runs_eight_turns_with_the_window_on_turns_two_to_eight(frequency):
    """Catches the frequency not reaching the trajectory, the window not starting after the
    first turn (1/f, not f), the stop time or reference end of the 1 Hz circle, and the
    description naming another frequency."""
    scene = vertical_circle("PDx", frequency=frequency)
    end = 8.0 / frequency
    assert scene.window == pytest.approx((1.0 / frequency, end), rel=1e-12)
    assert scene.reference_end == pytest.approx(end, rel=1e-12)
    assert scene.system.stop_time == pytest.approx(end + 3.0, rel=1e-12)
    reference = from_parameters(**scene.system.component("traj").parameters)
    for t in (0.0, 0.21, 0.4 * end, 0.99 * end):
        r = reference(t)
        assert (r.x, r.y) == pytest.approx(_circle(t, frequency), abs=1e-12)
    assert f"circle (7.23) at {frequency:g} Hz" in scene.description
    assert scene.name == "vertical_circle_PDx"


@pytest.mark.parametrize("name", ["vertical_circle_PDMDq", "vertical_circle_balanced_TCx"])
def test_gravity_pulls_down_the_vertical_plane_as_the_description_says(name):
    """The mechanism's plane vertical with world y up (vertical_circle's docstring): the plant's
    gravity is 9.81 m/s² along -y and nothing along x or z, the controller's model has the same in
    the plane, and the description's "gravity -9.81 m/s² along -y" is that vector.  Training
    sample 4203 [11] (gravity pointing up went unseen: the balanced and unbalanced runs track
    about as well either way)."""
    system = get_scene(name).system
    plant, ctrl = system.component("plant").parameters, system.component("ctrl").parameters
    assert (plant["gravity_x"], plant["gravity_y"], plant["gravity_z"]) == (0.0, -9.81, 0.0)
    assert (ctrl["gravity_x"], ctrl["gravity_y"]) == (0.0, -9.81)
    said = re.search(r"gravity (-?[0-9.]+) m/s² along (-?)y", get_scene(name).description)
    assert said and float(said.group(1)) == plant["gravity_y"] and said.group(2) == "-"
