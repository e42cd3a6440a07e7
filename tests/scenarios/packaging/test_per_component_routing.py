"""What the per-component package's entry points hand on (scenarios/packaging/per_component.py
``trial`` and ``export_per_component``): the scene, the system as exported (its observers
folded in when asked), the FMUs' variables read from the given folder, the goal and the
sub-steps, each to the step that uses it.  The runs and the files are replaced by recorders
(the real ones are covered by test_per_component.py's slow-ish fixtures, which take the
defaults); a quick check that non-default arguments arrive where they belong (training sample
4341 [21]: the scene and the system swapped in ``trial``, no test called it)."""
from __future__ import annotations

import pytest

from scenarios.packaging import per_component as pc
from scenarios.scenes.catalogue import get_scene

SCENE = "bench_circle_TCMDx"       # has two current observers to fold in


@pytest.fixture
def seen(monkeypatch):
    calls = []
    variables = {"made": "up"}

    def fake_variables(system, fmu_dir=None):
        calls.append(("variables", system, fmu_dir))
        return ("named", system), {"model": "file.fmu"}, variables

    monkeypatch.setattr(pc, "_variables", fake_variables)
    monkeypatch.setattr(pc, "choose_substeps_by_trial", lambda scene, system, v, goal=pc.TRACKING_GOAL: calls.append(
        ("trial", scene, system, v, goal)) or (6, {6: (1.0, 1.0)}, 0.0))
    monkeypatch.setattr(pc, "check_tracking", lambda scene, system, v, n: calls.append(("check", scene, system, v, n)))
    monkeypatch.setattr(pc, "per_component_system", lambda named, v, n: calls.append(("stepped", named, v, n))
                        or (("stepped", n), "timing"))
    monkeypatch.setattr("fmus.ssp.export.export_ssp", lambda stepped, path, fmu_dir, fmus=None: calls.append(
        ("export", stepped, path, fmu_dir, fmus)) or path)
    return calls, variables


@pytest.mark.parametrize("internal", [False, True])
def test_trial_runs_the_scene_against_the_exported_system_with_its_goal(seen, internal):
    """``trial(scene, internal, goal, fmu_dir)`` is ``choose_substeps_by_trial(scene, system,
    variables, goal)`` with system the scene's (observers folded in when ``internal``) and the
    variables read from ``fmu_dir``.  Catches the scene and the system swapped, the goal or the
    folder dropped, and the observers folded in when not asked (or not when asked)."""
    calls, variables = seen
    scene = get_scene(SCENE)
    system = pc.with_internal_observers(scene.system) if internal else scene.system
    assert (system == scene.system) is (not internal)
    assert pc.trial(scene, internal_observer=internal, goal=0.025, fmu_dir="some/fmus") == (6, {6: (1.0, 1.0)}, 0.0)
    assert calls == [("variables", system, "some/fmus"), ("trial", scene, system, variables, 0.025)]


def test_export_without_substeps_takes_the_trials_n_with_the_goal(seen, tmp_path):
    """A scene, no ``substeps``: the trial (with ``goal``) chooses n, the package is stepped at
    that n and exported to the path with the FMU folder and the files the system names.
    Catches the trial's n not used, the goal not passed, the tracking check run as well."""
    calls, variables = seen
    scene = get_scene(SCENE)
    path = tmp_path / "p.ssp"
    assert pc.export_per_component(scene, path, "fmu/dir", goal=0.03) == path
    system = scene.system
    assert calls == [("variables", system, "fmu/dir"), ("trial", scene, system, variables, 0.03),
                     ("stepped", ("named", system), variables, 6),
                     ("export", ("stepped", 6), path, "fmu/dir", {"model": "file.fmu"})]


def test_export_with_substeps_checks_the_tracking_at_that_n_and_runs_no_trial(seen, tmp_path):
    """A scene with ``substeps=3`` and internal observers: no trial; the tracking is checked at
    n = 3 on the system with the observers folded in, and the package stepped at 3.
    Catches the given n replaced by the trial's, the check skipped, the observers ignored."""
    calls, variables = seen
    scene = get_scene(SCENE)
    folded = pc.with_internal_observers(scene.system)
    pc.export_per_component(scene, tmp_path / "p.ssp", None, substeps=3, internal_observer=True)
    assert calls[:3] == [("variables", folded, None), ("check", scene, folded, variables, 3),
                         ("stepped", ("named", folded), variables, 3)]
    assert [c[0] for c in calls] == ["variables", "check", "stepped", "export"]


def test_a_system_is_exported_without_a_trial_or_a_check(seen, tmp_path):
    """A System (no scene to compare with): neither the trial nor the tracking check runs; the
    sub-steps go on as given (None: the fewest that hold the stages, chosen downstream)."""
    calls, variables = seen
    system = get_scene(SCENE).system
    pc.export_per_component(system, tmp_path / "s.ssp", "d")
    assert [c[0] for c in calls] == ["variables", "stepped", "export"] and calls[1][3] is None


def test_reproducibility_is_the_largest_relative_move_of_either_metric_under_either_shift(monkeypatch):
    """Runs replaced by made-up metrics keyed by the plant's start x0: nominal (2.0 mm, 0.5 N m),
    x0 + shift (2.02, 0.5), x0 - shift (2.0, 0.497): the largest |ratio - 1| is 1 %.  The shift
    is the one asked (3e-9 m, not the default) and moves only the plant's x0.  Catches a ratio
    not over the nominal run's metric, one metric or one sign left out, the shift's size or
    sign dropped, and another component shifted."""
    scene = get_scene(SCENE)
    plant = next(c for c in scene.system.components if "x0" in c.parameters)
    x0, shift = plant.parameters["x0"], 3e-9
    metrics = {x0: (2.0, 0.5), x0 + shift: (2.02, 0.5), x0 - shift: (2.0, 0.497)}
    others = {c.name: c for c in scene.system.components if c.name != plant.name}

    def tracking(scene_, system, every):
        assert every == 1 and system is scene_.system
        assert {c.name: c for c in system.components if c.name != plant.name} == others
        return metrics[system.component(plant.name).parameters["x0"]]

    monkeypatch.setattr("fmus.cosim.master.simulate", lambda system, mode=None: system)
    monkeypatch.setattr(pc, "_tracking", tracking)
    assert pc.reproducibility(scene, shift=shift) == pytest.approx(0.01, rel=1e-9)
    metrics[x0 - shift] = (2.0, 0.47)                                 # τ_ef 6 % under: the largest now
    assert pc.reproducibility(scene, shift=shift) == pytest.approx(0.06, rel=1e-9)


def test_jacobi_ratios_are_the_packages_metrics_over_ours_at_every_nth_row(monkeypatch):
    """Runs replaced by recorders: the package stepped at n = 4 is run with the Jacobi coupling
    and measured at every 4th row, ours (when not given) in process at every row; the ratios
    are (2.2 / 2.0, 0.45 / 0.5).  Catches a ratio inverted or multiplied, the two metrics
    crossed, the coupling or the row stride not passed."""
    runs = []

    def simulate(system, mode=None, coupling=None):
        runs.append((system, mode, coupling))
        return system

    monkeypatch.setattr("fmus.cosim.master.simulate", simulate)
    monkeypatch.setattr(pc, "per_component_system", lambda system, variables, n: (("stepped", system, n), None))
    monkeypatch.setattr(pc, "_tracking", lambda scene, result, every: (2.2, 0.45) if every == 4 else (2.0, 0.5))
    scene = get_scene(SCENE)
    assert pc.jacobi_ratios(scene, "system", {}, 4, ours=(2.0, 0.5)) == pytest.approx((1.1, 0.9), rel=1e-12)
    assert runs == [(("stepped", "system", 4), "inprocess", "jacobi")]
    runs.clear()
    assert pc.jacobi_ratios(scene, "system", {}, 4) == pytest.approx((1.1, 0.9), rel=1e-12)
    assert runs == [(scene.system, "inprocess", None), (("stepped", "system", 4), "inprocess", "jacobi")]


def test_tracking_measures_the_scenes_six_columns_and_time_at_every_nth_row(monkeypatch):
    """``_tracking(scene, result, 3)``: the metrics get the scene's x, y, x_d, y_d, tau1, tau2
    columns (the signals the scene names) and the time, each every 3rd row, and the run's
    completed flag; (e_ef, τ_ef) come back in that order.  Catches the stride on the wrong
    axis, a column of another signal, the completed flag lost, the two metrics crossed."""
    import numpy as np

    scene = get_scene(SCENE)
    t = np.arange(10) * 1e-3
    signals = {signal: float(k) + t for k, signal in enumerate(scene.columns.values())}

    class Result:
        time, completed = t, False

        def __getitem__(self, signal):
            return signals[signal]

    seen = {}
    monkeypatch.setattr("scenarios.run.metrics.scene_metrics", lambda sc, columns, wall, completed: seen.update(
        scene=sc, columns=columns, completed=completed) or {"e_ef_mm": 1.5, "tau_ef_Nm": 0.25})
    assert pc._tracking(scene, Result(), 3) == (1.5, 0.25)
    names = ("x", "y", "x_d", "y_d", "tau1", "tau2")
    assert seen["scene"] is scene and seen["completed"] is False and set(seen["columns"]) == {*names, "t"}
    for name in names:
        assert np.array_equal(seen["columns"][name], signals[scene.columns[name]][::3]), name
    assert np.array_equal(seen["columns"]["t"], t[::3])


@pytest.mark.parametrize("ours", [(float("nan"), 0.5), (2.0, float("inf")), (0.0, 0.5), (2.0, -0.1)])
def test_a_trial_against_a_run_of_ours_without_finite_positive_metrics_is_refused_before_any_n(monkeypatch, ours):
    """Seed 4001 [12]: our own run's e_ef is NaN (its members never stepped) and the trial tried every n up to
    1000 (minutes) before it refused; a ratio against 0, inf or NaN measures nothing, so it refuses at once,
    naming the scene and both metrics."""
    scene = get_scene(SCENE)
    monkeypatch.setattr("fmus.cosim.master.simulate", lambda system, mode=None: system)
    monkeypatch.setattr(pc, "_tracking", lambda scene, result, every: ours)
    tried = []
    monkeypatch.setattr(pc, "jacobi_ratios", lambda *args: tried.append(args) or (1.0, 1.0))
    with pytest.raises(ValueError) as refused:
        pc.choose_substeps_by_trial(scene, scene.system, {})
    assert str(refused.value) == (f"scene {SCENE}: our master's own run gives e_ef = {ours[0]!r}, "
                                  f"tau_ef = {ours[1]!r}: no sub-step count can be chosen against it; pass substeps")
    assert tried == []
