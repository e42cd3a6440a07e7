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
