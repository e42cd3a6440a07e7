"""scenarios/packaging/per_component.py's tracking check at its bound, hit exactly, without a run
(``jacobi_ratios`` replaced by given ratios; issue 31, session 44: boundaries of the generalised
training sample)."""
from __future__ import annotations

import math
import warnings
from types import SimpleNamespace

import pytest

from fmus.cosim.system import Component, Connection, System
from scenarios.packaging import per_component
from scenarios.packaging.per_component import PHASE, TRACKING_BOUND, TrackingWarning, check_tracking, component_timing

SCENE = SimpleNamespace(name="bench_circle_PDx")
SYSTEM = SimpleNamespace(step=1e-3, components=(SimpleNamespace(parameters={"x0": 0.0}),
                                                 SimpleNamespace(parameters={"strategy": "PDx"})))


def _check(monkeypatch, ratios, **bound):
    asked = []
    monkeypatch.setattr(per_component, "jacobi_ratios", lambda *a: asked.append(a) or ratios)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        back = check_tracking(SCENE, SYSTEM, {"v": 1}, 4, **bound)
    assert back == ratios and asked == [(SCENE, SYSTEM, {"v": 1}, 4)]
    return [w for w in caught if issubclass(w.category, TrackingWarning)]


def test_ratios_off_by_exactly_the_bound_track_and_a_float_beyond_warns(monkeypatch):
    """"off ours by more than bound": with bound 2^-4 (exact) the ratios 1 +- 2^-4 track (no
    warning), either ratio one float farther warns.  Catches ``>=`` for ``>`` and one ratio
    of the two left out of the check."""
    edge = 0.0625
    assert _check(monkeypatch, (1 + edge, 1 - edge), bound=edge) == []
    for ratios in ((math.nextafter(1 + edge, 2.0), 1.0), (1.0, math.nextafter(1 - edge, 0.0))):
        assert len(_check(monkeypatch, ratios, bound=edge)) == 1, ratios


def test_the_default_bound_is_issue_26s_five_percent_and_the_warning_names_what_it_measured(monkeypatch):
    """Default bound 5 % (issue 26): ratios 1.04 / 0.97 track, 1.06 warns, naming the scene,
    the controller's strategy, n, the sub-step h, both ratios and the bound."""
    assert TRACKING_BOUND == 0.05
    assert _check(monkeypatch, (1.04, 0.97)) == []
    [w] = _check(monkeypatch, (1.06, 0.97))
    text = str(w.message)
    assert text.startswith("scene bench_circle_PDx (strategy PDx): its per-component package at 4 sub-step(s) "
                           "per period (h = 0.00025 s) does not track in a Jacobi master: e_ef x1.060, "
                           "tau_ef x0.970 of parcosim run's (bound x1.05)")


def _var(causality, variability="continuous"):
    return SimpleNamespace(causality=causality, variability=variability)


def test_a_sampled_components_period_exactly_1e_12_relative_off_the_scenes_is_its_period():
    """The period check refuses a T off the scene's step by *more than* 1e-12 relative.  At the
    step 5e15 * 2^-62 s (about 1.08 ms) 1e-12 of it is 5000 units of its last place, so
    T = step (1 +- 1e-12) are exact floats on the boundary: accepted (the same phases as at
    T = step); one float farther is refused naming the component.  Catches ``>=`` for ``>``."""
    step = 5e15 * 2.0 ** -62
    assert 1e-12 * step == 5000 * math.ulp(step)                   # the boundary is a float difference

    def system(T):
        comps = (Component("a", "A", {"T": T}), Component("p", "P", {}))
        return System(comps, (Connection("p.y", "a.u"), Connection("a.y", "p.u")), ("p.y",), 1.0, step)

    variables = {"a": {"u": _var("input"), "y": _var("output", "discrete"), PHASE: _var("parameter", "fixed")},
                 "p": {"u": _var("input"), "y": _var("output")}}
    nominal = component_timing(system(step), variables)
    for T in (step + 1e-12 * step, step - 1e-12 * step):
        assert abs(T - step) == 1e-12 * step
        assert component_timing(system(T), variables) == nominal, T
    for T in (math.nextafter(step + 1e-12 * step, 1.0), math.nextafter(step - 1e-12 * step, 0.0)):
        with pytest.raises(ValueError, match=rf"a\.T = {T!r} s: the per-component package samples every component "
                                             rf"at the scene's period {step!r} s"):
            component_timing(system(T), variables)


def test_a_one_stage_chain_samples_on_the_second_sub_step_from_two_sub_steps_on():
    """The module: a one-stage chain (the sampled component reads the plant directly) samples on
    the period's second sub-step -- when the period has one (n >= 2): phase 1 at n = 2 and 4,
    0 at n = 1.  Catches the shift applied from n = 3 only (``>`` for ``>=``)."""
    step = 1e-3
    system = System((Component("a", "A", {}), Component("p", "P", {})),
                    (Connection("p.y", "a.u"), Connection("a.y", "p.u")), ("p.y",), 1.0, step)
    variables = {"a": {"u": _var("input"), "y": _var("output", "discrete"), PHASE: _var("parameter", "fixed")},
                 "p": {"u": _var("input"), "y": _var("output")}}
    assert component_timing(system, variables, 1).phases == {"a": 0}
    assert component_timing(system, variables, 2).phases == {"a": 1}
    assert component_timing(system, variables, 4).phases == {"a": 1}


def test_the_trial_measures_the_scenes_floor_only_when_the_first_n_misses_the_goal_by_more_than_it(monkeypatch):
    """A first try whose deviation is exactly the goal (2^-7, so 1 - 2^-7 is exact) is within it:
    taken without measuring the scene's own floor (0.0 returned); a float more measures it
    (then within goal + floor: taken at once with that floor).  Catches ``>=`` for ``>``."""
    goal = 2.0 ** -7
    floors = []
    ratios = {}
    monkeypatch.setattr(per_component, "_tracking", lambda scene, result, every: (1.0, 1.0))
    monkeypatch.setattr("fmus.cosim.master.simulate", lambda *a, **kw: None)
    monkeypatch.setattr(per_component, "component_timing", lambda system, variables: SimpleNamespace(substeps=4))
    monkeypatch.setattr(per_component, "jacobi_ratios", lambda scene, system, variables, n, ours: ratios[n])
    monkeypatch.setattr(per_component, "reproducibility", lambda scene: floors.append(scene) or 0.25)
    scene = SimpleNamespace(name="made_up", system=None)
    ratios[4] = (1.0, 1.0 - goal)
    assert per_component.choose_substeps_by_trial(scene, None, {}, goal=goal) == (4, {4: ratios[4]}, 0.0)
    assert floors == []
    ratios[4] = (math.nextafter(1.0 + goal, 2.0), 1.0)
    assert per_component.choose_substeps_by_trial(scene, None, {}, goal=goal) == (4, {4: ratios[4]}, 0.25)
    assert floors == [scene]
