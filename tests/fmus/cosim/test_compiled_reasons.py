"""The reasons compiled mode gives for running in process instead, each read whole from the
fallback's warning and ``Result.extra["fallback"]``: the setting, its value and the rule it
breaks (fmus/cosim/compiled.py ``check_compilable``, fmus/cosim/compiled_adapters.py; issue 31:
these reasons were only matched by a word or two, or not at all)."""
from __future__ import annotations

from dataclasses import replace

import pytest

from fmus.cosim.master import simulate
from scenarios.scenes.catalogue import get_scene


def _system(component=None, **parameters):
    """bench_circle_PDq for three steps, ``component``'s parameters changed."""
    system = get_scene("bench_circle_PDq").system
    components = tuple(replace(c, parameters={**c.parameters, **parameters}) if c.name == component else c
                       for c in system.components)
    return replace(system, components=components, stop_time=0.003)


def _fallback(system, **options):
    with pytest.warns(UserWarning) as caught:
        result = simulate(system, mode="compiled", **options)
    reason = result.extra["fallback"]
    assert result.mode == "inprocess" and result.error is None and len(result.time) == 4
    assert [str(w.message) for w in caught] == [f"compiled mode: {reason}; running in process instead"]
    return reason


@pytest.mark.parametrize("options, reason", [
    ({"coupling": "jacobi"}, "coupling 'jacobi': the compiled loop is Gauss-Seidel only"),
    ({"retry_substeps": 3}, "retry_substeps: retried steps need FMU states, which the compiled loop does not take"),
])
def test_a_run_option_the_compiled_loop_lacks_falls_back_with_its_whole_reason(options, reason):
    """Catches the Jacobi coupling or a retry taken into the compiled loop, or a reason naming
    another option."""
    assert _fallback(_system(), **options) == reason


def test_a_derivator_sampling_slower_than_the_step_falls_back_naming_h_t_and_the_phase():
    """The derivator sampling every second step (T = 2 h) on the second sub-step (the Integer
    ``sample_phase`` 1 of 0..1): its kernel has no sub-step counter, so the reason names h, T and
    the phase.  Catches the rate check dropped or the values of another component named."""
    assert _fallback(_system("deriv", T=0.002, sample_phase=1)) == (
        "component deriv: steps h = 0.001 s with T = 0.002 s, sample_phase = 1: the compiled kernel samples on "
        "every step (h = T, sample_phase 0 only)")


def test_a_derivator_holding_its_first_step_falls_back_naming_the_setting():
    """Catches ``hold_first_step`` ignored by the compiled loop (which samples on the first step)."""
    assert _fallback(_system("deriv", hold_first_step=True)) == (
        "component deriv: hold_first_step = True: the compiled kernel samples on the first step too")
