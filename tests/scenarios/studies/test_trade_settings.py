"""scenarios/studies/trade/settings.py: each setting of the trade study applied to a bench scene
changes what its text says and nothing else; the sample-time settings at 2 and 4 ms; settings
that do not apply give None (issue 31: sample times other than 1 ms, switches off their
defaults; the scenes compared as data, nothing runs)."""
from __future__ import annotations

import pytest

from scenarios.scenes import get_scene
from scenarios.scenes.transforms import SAMPLE_TIME_MODELS
from scenarios.studies.trade.settings import SAMPLE_TIMES, settings

SCENE = get_scene("bench_circle_TCMDx")
BY_NAME = {s.name: s for s in settings()}


def _differences(before, after):
    """{component: (parameters changed or added, substeps if changed)} between two scenes."""
    old = {c.name: c for c in before.system.components}
    found = {}
    for c in after.system.components:
        o = old.get(c.name)
        if o is None or o.model != c.model:
            found[c.name] = "new"
            continue
        changed = {k: v for k, v in c.parameters.items() if o.parameters.get(k, object()) != v}
        if changed or c.substeps != o.substeps:
            found[c.name] = (changed, c.substeps)
    return found


def test_the_names_are_unique_and_the_quick_sweep_is_part_of_the_full_one():
    """Catches two trade settings of one name (their rows would overwrite each other), defaults not first,
    or a quick setting the full sweep does not have."""
    names = [s.name for s in settings()]
    assert len(names) == len(set(names)) and names[0] == "defaults"
    assert {s.name for s in settings(quick=True)} <= set(names)
    assert {s.kind for s in settings()} == {"accuracy", "fidelity"}


@pytest.mark.parametrize("name, expected", [
    ("plant rk4 substeps=4", {"plant": ({"substeps": 4}, 1)}),
    ("plant dopri5 rtol=1e-10", {"plant": ({"method": "dopri5", "rtol": 1e-10, "atol": 1e-13}, 1)}),
    ("plant multirate 4", {"plant": ({}, 4)}),
    ("drive euler", {"drive1": ({"method": "euler"}, 1), "drive2": ({"method": "euler"}, 1)}),
    ("group 8", {"drive1": ({}, 8), "drive2": ({}, 8), "plant": ({}, 8)}),
    ("torque end", {"drive1": ({"torque_output": "end"}, 1), "drive2": ({"torque_output": "end"}, 1)}),
    ("table 2.5 mm", {"ctrl": ({"grid_step": 0.0025}, 1)}),
    ("viscous b=1e-7", {"drive1": ({"b": 1e-7}, 1), "drive2": ({"b": 1e-7}, 1)}),
    ("no viscous friction", {"drive1": ({"b": 0.0, "b_design": 0.0001226}, 1),      # the controller keeps
                             "drive2": ({"b": 0.0, "b_design": 0.0002039}, 1)}),    # the motors' b (Table 16, 18)
    # each value as the setting's name or text states it (siblings of seed 4001 [154])
    ("plant dopri5 rtol=1e-6", {"plant": ({"method": "dopri5", "rtol": 1e-6, "atol": 1e-9}, 1)}),
    ("plant baumgarte=0", {"plant": ({"baumgarte": 0.0}, 1)}),
    ("plant project", {"plant": ({"project": True}, 1)}),
    ("m0 = 0.05 kg", {"plant": ({"m0": 0.05}, 1)}),
    ("vertical plane", {"plant": ({"gravity_y": -9.81}, 1)}),        # gravity (0, -9.81, 0) m/s²
    ("model error 20 %", {"ctrl": ({"model_error": 0.20}, 1)}),
    ("table 10 mm", {"ctrl": ({"grid_step": 0.010}, 1)}),
])
def test_a_setting_changes_what_it_says_and_nothing_else(name, expected):
    """Catches a setting applied to the wrong component, its sub-steps given to the others,
    or a parameter of another setting."""
    built = BY_NAME[name].build(SCENE)
    assert _differences(SCENE, built) == expected
    assert built.system.step == SCENE.system.step and built.system.connections == SCENE.system.connections


@pytest.mark.parametrize("T", SAMPLE_TIMES)
def test_the_sample_time_settings_step_and_sample_everything_at_T(T):
    """Both sample times (2 and 4 ms) and the ideal-sensors variant: the master's step and every
    designed component's T; the variant has no drives or derivator and the same T."""
    assert T in (2e-3, 4e-3)
    built = BY_NAME[f"sample {1e3 * T:g} ms"].build(SCENE)
    assert built.system.step == T and built.system.stop_time == SCENE.system.stop_time
    designed = [c for c in built.system.components if c.model in SAMPLE_TIME_MODELS]
    assert len(designed) == 6 and all(c.parameters["T"] == T for c in designed)
    ideal = BY_NAME[f"ideal + exact sensors, sample {1e3 * T:g} ms"].build(SCENE)
    assert ideal.system.step == T
    models = [c.model for c in ideal.system.components]
    assert "DCMotorDrive" not in models and "Derivator" not in models
    assert all(c.parameters["T"] == T for c in ideal.system.components if c.model in SAMPLE_TIME_MODELS)


def test_settings_that_do_not_apply_give_none():
    """The thesis' simulation scene has no drives and is no bench scene."""
    thesis = get_scene("thesis_sim_circle")
    for name in ("drive euler", "group 4", "drives in plant, substeps=8", "no observer", "torque end"):
        assert BY_NAME[name].build(thesis) is None, name
    assert BY_NAME["plant rk4 substeps=4"].build(thesis) is not None
    assert BY_NAME["jacobi"].coupling == "jacobi" and BY_NAME["fmu"].mode == "fmu"


def test_the_quick_sweep_is_the_nine_settings_docs_trade_md_names_fidelity_switches_included():
    """docs/trade.md, 'The quick variant': defaults, plant RK4 x4, drive Euler, group 4, torque
    end, drives in plant x8, Jacobi, ideal actuators and no observer.  Catches the quick sweep
    losing its fidelity settings (or gaining the full sweep's), seed 4001 [154]."""
    quick = settings(quick=True)
    assert [s.name for s in quick] == ["defaults", "plant rk4 substeps=4", "drive euler", "group 4", "torque end",
                                       "drives in plant, substeps=8", "jacobi", "ideal actuators", "no observer"]
    assert [s.kind for s in quick] == ["accuracy"] * 7 + ["fidelity"] * 2
    # each quick setting is the full sweep's setting of that name: same kind, text and options
    for s in quick:
        full = BY_NAME[s.name]
        assert (s.kind, s.what, s.mode, s.coupling) == (full.kind, full.what, full.mode, full.coupling), s.name
        assert _differences(full.build(SCENE), s.build(SCENE)) == {}, s.name


def test_the_fmu_variant_of_the_drives_in_plant_is_that_setting_through_fmus():
    """'drives in plant, substeps=8, fmu' builds the scene 'drives in plant, substeps=8' builds and
    runs it through the FMUs."""
    fmu, plain = BY_NAME["drives in plant, substeps=8, fmu"], BY_NAME["drives in plant, substeps=8"]
    assert (fmu.mode, plain.mode) == ("fmu", "inprocess") and fmu.coupling == plain.coupling
    assert _differences(plain.build(SCENE), fmu.build(SCENE)) == {}
    assert fmu.build(SCENE).system.component("plant").parameters["substeps"] == 8
