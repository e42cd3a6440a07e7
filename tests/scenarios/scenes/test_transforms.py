"""scenarios/scenes/transforms.py on scenes built here, every output compared whole with what
the transform's docstring says (issue 31: configurations the tests never leave, such as drives
wired to the other joint, drive parameters away from their defaults, a sample time other than
1 ms)."""
from __future__ import annotations

import math
from dataclasses import replace

import pytest

from fmus.cosim.system import Component, Connection, System
from scenarios.scenes import get_scene
from scenarios.scenes.scene import Scene
from scenarios.scenes.transforms import SAMPLE_TIME_MODELS, drive_joints, drives_in_plant, with_sample_time


def _crosswise(drive1=None, drive2=None) -> Scene:
    """A bench-like scene whose drive ``dA`` drives joint 2 and ``dB`` joint 1 (the names and
    the joints disagree, so a transform that takes a drive's joint from its name or its
    position shows), each drive with its own parameters."""
    drive1 = {"preset": "motor1", "mode": "current", "T": 2e-3, "torque_output": "mean", "method": "exact",
              **(drive1 or {})}
    drive2 = {"preset": "motor2", "mode": "current", "T": 2e-3, "torque_output": "end", "method": "rk4",
              **(drive2 or {})}
    components = (Component("ctrl", "PositionController", {"T": 2e-3}),
                  Component("dA", "DCMotorDrive", drive1),
                  Component("dB", "DCMotorDrive", drive2),
                  Component("obs", "CurrentObserver", {"preset": "motor2"}),
                  Component("plant", "FiveBarPlant", {"preset": "bench", "x0": -0.002}))
    connections = (Connection("ctrl.i_ref1", "dB.i_ref"), Connection("ctrl.i_ref2", "dA.i_ref"),
                   Connection("plant.dq2", "dA.omega"), Connection("dA.tau", "plant.tau2"),
                   Connection("plant.dq1", "dB.omega"), Connection("dB.tau", "plant.tau1"),
                   Connection("dA.v", "obs.v"), Connection("obs.i_hat", "dA.i_hat"),
                   Connection("plant.q1_enc", "ctrl.q1"), Connection("plant.q2_enc", "ctrl.q2"))
    system = System(components=components, connections=connections,
                    record=("plant.x", "dA.i", "dB.i", "dA.v", "dB.tau"), stop_time=0.1, step=2e-3)
    columns = {"x": "plant.x", "i_a": "dA.i", "i_b": "dB.i", "tau_b": "dB.tau"}
    return Scene("crosswise", "two drives wired crosswise", system, columns, (0.0, 0.1), 0.1, "TCMDx")


def test_drives_wired_crosswise_move_to_the_joint_they_drive():
    """Catches a drive's variables renamed by its order or its name (``drive1`` -> 1) instead of
    the joint its torque drives, a connection inside the plant kept, or one outside it lost."""
    assert drive_joints(_crosswise().system, "plant") == {"dA": 2, "dB": 1}
    scene = drives_in_plant(_crosswise(), substeps=3)
    pairs = {(c.source, c.target) for c in scene.system.connections}
    assert pairs == {("ctrl.i_ref1", "plant.i_ref1"), ("ctrl.i_ref2", "plant.i_ref2"),
                     ("plant.v2", "obs.v"), ("obs.i_hat", "plant.i_hat2"),
                     ("plant.q1_enc", "ctrl.q1"), ("plant.q2_enc", "ctrl.q2")}
    assert scene.system.record == ("plant.x", "plant.i2", "plant.i1", "plant.v2", "plant.tau1")
    assert scene.columns == {"x": "plant.x", "i_a": "plant.i2", "i_b": "plant.i1", "tau_b": "plant.tau1"}
    assert [(c.name, c.model) for c in scene.system.components] == [
        ("ctrl", "PositionController"), ("obs", "CurrentObserver"), ("plant", "ActuatedFiveBarPlant")]
    assert scene.system.step == 2e-3 and scene.system.stop_time == 0.1
    assert scene.description == "two drives wired crosswise; drives integrated in the plant"


def test_drive_parameters_move_with_the_joint_suffix_and_the_shared_ones_once():
    """Every drive parameter away from its default lands on the plant with the suffix of the
    joint it drives; ``mode`` and ``T`` once; ``method`` and ``torque_output`` dropped; the
    plant's own parameters and ``plant_parameters`` kept.  Catches a suffix from the wrong
    drive, a shared key suffixed, a coupling-only key carried over, a plant parameter lost."""
    scene = drives_in_plant(_crosswise({"R": 1.2345678901234567, "omega0": 0.0}, {"L": 3.3e-4, "i0": 0.0}),
                            substeps=3)
    assert scene.system.component("plant").parameters == {
        "preset": "bench", "x0": -0.002, "substeps": 3, "mode": "current", "T": 2e-3,
        "preset2": "motor1", "R2": 1.2345678901234567, "preset1": "motor2", "L1": 3.3e-4}


@pytest.mark.parametrize("key, value", [("omega0", 0.5), ("i0", -1e-3)])
def test_a_drive_started_moving_or_with_a_current_is_refused_naming_it(key, value):
    """Catches the start-at-rest check dropped or turned round (zero is accepted, above)."""
    with pytest.raises(ValueError, match=rf"drive dB starts with {key} = {value!r}; the actuated plant starts at rest"):
        drives_in_plant(_crosswise(drive2={key: value}))


@pytest.mark.parametrize("key, first, second", [("mode", "current", "voltage"), ("T", 2e-3, 1e-3)])
def test_drives_that_differ_in_a_shared_parameter_are_refused_naming_both_values(key, first, second):
    """Catches the comparison of the shared ``mode``/``T`` dropped (the second drive's value
    would silently win or be lost)."""
    with pytest.raises(ValueError, match=rf"the drives differ in {key} \({first!r}, {second!r}\)"):
        drives_in_plant(_crosswise({key: first}, {key: second}))


def test_a_drive_whose_torque_drives_both_joints_or_none_is_refused():
    """Catches ``len(driven) != 1`` loosened to ``== 0`` or ``> 1`` alone."""
    scene = _crosswise()
    both = scene.system.connections + (Connection("dA.tau", "plant.tau1"),)
    both = tuple(c for c in both if c.target != "plant.tau1" or c.source == "dA.tau")
    with pytest.raises(ValueError, match=r"drive dA: its tau must drive exactly one of plant.tau1/tau2"):
        drive_joints(replace(scene.system, connections=both), "plant")
    none = tuple(c for c in scene.system.connections if c.source != "dB.tau")
    with pytest.raises(ValueError, match=r"drive dB: its tau must drive exactly one of plant.tau1/tau2"):
        drive_joints(replace(scene.system, connections=none), "plant")


def test_with_sample_time_sets_the_step_and_each_designed_components_T_and_nothing_else():
    """At 2.5 ms (not a multiple of the default): the step and the T of every model designed for
    one, an existing T replaced, every other component the same object.  Catches a model left
    out of the list, T written to the wrong components, a step not changed with it."""
    base = get_scene("bench_circle_TCMDx")
    scene = with_sample_time(base, 2.5e-3)
    assert scene.system.step == 2.5e-3
    assert scene.description == base.description + "; sample time 2.5 ms"
    for before, after in zip(base.system.components, scene.system.components, strict=True):
        if before.model in SAMPLE_TIME_MODELS:
            assert after.parameters == {**before.parameters, "T": 2.5e-3}
        else:
            assert after is before
    again = with_sample_time(scene, 4e-3)
    assert {c.parameters.get("T") for c in again.system.components if c.model in SAMPLE_TIME_MODELS} == {4e-3}
    assert sum(c.model in SAMPLE_TIME_MODELS for c in base.system.components) == 6   # deriv, ctrl, 2 obs, 2 drives


@pytest.mark.parametrize("T", [0.0, -1e-3, math.nan])
def test_a_sample_time_that_is_not_positive_is_refused_naming_it(T):
    """Catches ``not (T > 0)`` turned into ``T < 0`` (0 and NaN would pass)."""
    with pytest.raises(ValueError, match=rf"sample time T = {T!r} s must be > 0"):
        with_sample_time(get_scene("bench_circle_TCMDx"), T)


def test_with_fmu_files_swaps_the_named_instances_and_says_so(tmp_path):
    """Catches the description left unchanged, a replacement given to the wrong instance, or
    a scene changed when nothing is replaced (only an existing ``.fmu`` path is taken: an
    empty file of that name is enough here, nothing runs it)."""
    from scenarios.scenes.transforms import with_fmu_files

    base = _crosswise()
    assert with_fmu_files(base, {}) is base
    fmu = tmp_path / "my drive.fmu"
    fmu.write_bytes(b"")
    scene = with_fmu_files(base, {"dB": fmu})
    assert scene.description == "two drives wired crosswise; FMU files: dB=my drive.fmu"
    assert [c.model for c in scene.system.components] == [
        "PositionController", "DCMotorDrive", str(fmu.resolve()), "CurrentObserver", "FiveBarPlant"]
    assert scene.system.component("dB").parameters == base.system.component("dB").parameters
    assert scene.system.connections == base.system.connections


def test_drives_in_plant_refuses_a_scene_without_one_plant_or_with_a_miswired_drive_naming_the_scene():
    """A scene without a FiveBarPlant (the wheeled pendulum's) and the crosswise scene with a
    drive fed the other joint's speed: each refused with the scene's name and the reason.
    Catches the plant count's check skipped and the wiring's reason not naming the scene."""
    with pytest.raises(ValueError) as refusal:
        drives_in_plant(get_scene("pendulum_balance"))
    assert str(refusal.value) == "scene pendulum_balance: drives_in_plant needs one FiveBarPlant, found 0"
    scene = _crosswise()
    crossed = tuple(Connection("plant.dq1", c.target) if c.target == "dA.omega" else c
                    for c in scene.system.connections)
    with pytest.raises(ValueError) as refusal:
        drives_in_plant(replace(scene, system=replace(scene.system, connections=crossed)))
    assert str(refusal.value) == "scene crosswise: drive dA: omega must be plant.dq2 (got plant.dq1)"


@pytest.mark.parametrize("changes, message", [
    ({"electrics": "magic"}, "electrics = 'magic'; valid: full, euler, quasi_static, ideal"),
    ({"friction": "glue"}, "friction = 'glue'; valid: "),
    ({"friction": "lugre", "coulomb": False},
     "friction = 'lugre' models the dry friction that coulomb = False removes"),
    ({"electrics": "ideal", "pwm_counts": 960},
     "electrics = 'ideal' has no drives for friction, pwm_counts, current_offset, current_noise, noise_seed or "
     "drive_parameters"),
    ({"electrics": "ideal", "drive_parameters": (("R", 1.0),)}, "electrics = 'ideal' has no drives for ")])
def test_a_fidelity_that_contradicts_itself_is_refused_word_for_word(changes, message):
    """Catches each of the bench fidelity's checks skipped or naming another value."""
    from scenarios.scenes.thesis import Fidelity

    with pytest.raises(ValueError) as refusal:
        Fidelity(**changes)
    assert str(refusal.value).startswith(message)
    assert Fidelity(electrics="ideal").drive_options() == {} and Fidelity(friction="lugre").drive_options() == {
        "friction": "lugre"}


def test_a_bench_of_an_unknown_strategy_is_refused_listing_the_valid_ones():
    """Catches a bench scene built for a strategy no controller knows (refused later, or not)."""
    from controller.strategies import ALL_STRATEGY_NAMES
    from scenarios.scenes.thesis import bench

    with pytest.raises(ValueError) as refusal:
        bench("PIDx")
    assert str(refusal.value) == f"strategy = 'PIDx'; valid: {', '.join(ALL_STRATEGY_NAMES)}"
