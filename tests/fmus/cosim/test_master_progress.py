"""What ``simulate`` reports to ``progress`` (fmus/cosim/master.py, compiled.py), in process and
compiled, at two lengths of run: fractions of steps done (k / N, a whole number of steps), rising,
about a hundred of them, the last 1 for a run that reached its stop time (issue 31: "fmus other";
every reported value read back)."""
from __future__ import annotations

from dataclasses import replace

import pytest

from fmus.cosim.master import simulate
from scenarios.scenes.catalogue import get_scene


@pytest.mark.parametrize("mode", ["inprocess", "compiled"])
@pytest.mark.parametrize("stop_time", [0.05, 0.25])
def test_progress_is_the_fraction_of_steps_done_rising_to_one(mode, stop_time):
    """Catches a fraction over the wrong total (steps + 1, the rows), a count of steps not
    whole, a fraction reported twice or going back, the last one missing, and a report at every
    step of a long run (or none of a short one)."""
    system = replace(get_scene("thesis_sim_circle").system, stop_time=stop_time)
    fractions = []
    result = simulate(system, mode=mode, progress=fractions.append)
    steps = system.steps
    assert result.error is None and result.mode == mode and steps == round(stop_time / 1e-3)
    done = [f * steps for f in fractions]
    assert all(abs(d - round(d)) < 1e-9 and 1 <= round(d) <= steps for d in done)
    assert all(b > a for a, b in zip(fractions, fractions[1:])) and fractions[-1] == 1.0
    assert min(steps, 50) <= len(fractions) <= min(steps, 200)        # about a hundred (every step of a short run)


@pytest.mark.parametrize("mode", ["inprocess", "compiled"])
@pytest.mark.parametrize("stop_time", [0.03, 0.25])
def test_progress_reports_every_hundredth_of_the_steps_exactly(mode, stop_time):
    """Counted by hand: a report after every max(1, N // 100) steps, so 30 steps report each step
    (30 reports) and 250 steps every second one (k = 2, 4, ..., 250: 125 reports), each k / N.
    Catches the stride off (N // 50, at least 2) or a report on another step."""
    system = replace(get_scene("thesis_sim_circle").system, stop_time=stop_time)
    fractions = []
    simulate(system, mode=mode, progress=fractions.append)
    steps = system.steps
    stride = {30: 1, 250: 2}[steps]
    assert fractions == pytest.approx([k / steps for k in range(stride, steps + 1, stride)], rel=0, abs=1e-12)


def test_an_in_process_run_whose_steps_are_no_multiple_of_the_stride_still_reports_one_at_the_end():
    """The module's promise: the last fraction is 1 for a run that reached its stop time, also
    when N (350) is no multiple of the stride (3)."""
    system = replace(get_scene("thesis_sim_circle").system, stop_time=0.35)
    fractions = []
    result = simulate(system, mode="inprocess", progress=fractions.append)
    assert result.error is None and fractions[-1] == 1.0
