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
