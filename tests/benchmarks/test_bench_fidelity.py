"""scenarios/scenes/thesis.py's Fidelity switches: each switch off its default changes the bench
scene as its docstring says and nothing else (components' parameters and the wiring compared
with the default scene's), issue 31's second pattern (switches and zero-by-default values set)."""
from __future__ import annotations

import pytest

from motor import get_motor_preset
from scenarios.scenes.thesis import Fidelity, bench

BASE = bench("TCMDx", "circle")


def _changes(scene):
    """({component: changed or added parameters, or "removed"}, connections added, removed)."""
    old = {c.name: c for c in BASE.system.components}
    new = {c.name: c for c in scene.system.components}
    changed = {name: "removed" for name in old if name not in new}
    for name, c in new.items():
        d = {k: v for k, v in c.parameters.items() if old[name].parameters.get(k, "absent") != v}
        if d:
            changed[name] = d
    pairs = {(c.source, c.target) for c in scene.system.connections}
    before = {(c.source, c.target) for c in BASE.system.connections}
    return changed, pairs - before, before - pairs


@pytest.mark.parametrize("switches, expected", [
    ({"coulomb": False}, {"drive1": {"mu": 0.0}, "drive2": {"mu": 0.0}}),
    ({"link_inertias": False}, {"plant": {"link_inertias": False}}),
    ({"m0": 0.05}, {"plant": {"m0": 0.05}}),
    ({"gravity": (0.0, -9.81, 0.0)}, {"plant": {"gravity_y": -9.81}}),
    ({"model_error": 0.2}, {"ctrl": {"model_error": 0.2}}),
    ({"counter_masses": (0.1, 0.2)}, {"ctrl": {"counter_mass1": 0.1, "counter_mass2": 0.2},
                                      "plant": {"counter_mass1": 0.1, "counter_mass2": 0.2}}),
    ({"model_gravity": True, "gravity": (0.0, -9.81, 0.0)}, {"ctrl": {"gravity_x": 0.0, "gravity_y": -9.81},
                                                             "plant": {"gravity_y": -9.81}}),
    ({"delay_steps": 1}, {"ctrl": {"delay_steps": 1}}),
    ({"electrics": "euler"}, {"drive1": {"method": "euler"}, "drive2": {"method": "euler"}}),
    ({"electrics": "quasi_static"}, {"drive1": {"method": "quasi_static"}, "drive2": {"method": "quasi_static"}}),
])
def test_a_parameter_switch_reaches_the_components_it_names_and_no_other(switches, expected):
    """Catches a switch given to the other drive only, to the plant but not the controller's
    model (counter-masses, model gravity), or a value that is not the one asked."""
    assert _changes(bench("TCMDx", "circle", fidelity=Fidelity(**switches))) == (expected, set(), set())


def test_without_viscous_friction_the_current_loop_stays_designed_for_the_motors_b():
    """Catches switching viscous friction off also changing the current controller's design (b_design
    follows b to 0), or changing other components."""
    changed, added, removed = _changes(bench("TCMDx", "circle", fidelity=Fidelity(viscous=False)))
    assert changed == {f"drive{j}": {"b": 0.0, "b_design": get_motor_preset(f"motor{j}").b} for j in (1, 2)}
    assert get_motor_preset("motor1").b != get_motor_preset("motor2").b and not added and not removed


def test_exact_angles_rewire_the_encoders_readers_to_the_angles():
    """Catches exact angles that leave a reader (controller or derivator) on the quantised encoder, or
    rewire something else."""
    changed, added, removed = _changes(bench("TCMDx", "circle", fidelity=Fidelity(encoder=False)))
    assert changed == {}
    for j in (1, 2):
        for reader in ("ctrl", "deriv"):
            assert (f"plant.q{j}", f"{reader}.q{j}") in added and (f"plant.q{j}_enc", f"{reader}.q{j}") in removed
    assert len(added) == len(removed) == 4


def test_without_observers_the_current_loops_read_the_drives_own_current():
    """Catches removing the observers without rewiring the current loops to the drives' own current
    (dangling inputs held at 0)."""
    changed, added, removed = _changes(bench("TCMDx", "circle", fidelity=Fidelity(observer=False)))
    assert changed == {"obs1": "removed", "obs2": "removed"}
    assert added == {("drive1.i", "drive1.i_hat"), ("drive2.i", "drive2.i_hat")}
    assert all("obs" in s or "obs" in t for s, t in removed) and len(removed) == 6


def test_without_a_derivator_the_controller_and_observers_read_the_exact_speeds():
    """No derivator; its readers take plant.dq<j>; the accelerations are left at their start 0."""
    changed, added, removed = _changes(bench("TCMDx", "circle", fidelity=Fidelity(derivator=False)))
    assert changed == {"deriv": "removed"}
    assert added == {("plant.dq1", "ctrl.dq1"), ("plant.dq1", "obs1.omega"), ("plant.dq2", "ctrl.dq2"),
                     ("plant.dq2", "obs2.omega")}
    assert not any(t.startswith("ctrl.ddq") for _, t in added)
    assert all(s.startswith("deriv.") or t.startswith("deriv.") for s, t in removed)
