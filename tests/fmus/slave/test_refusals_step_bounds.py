"""The bounds every parcosim FMU puts on a step (fmus/slave/base.py ``MIN_STEP``, ``MAX_TIME``) are
the ones docs/extremes.md publishes ("below `MIN_STEP` = 1e-9 s, or ending after `MAX_TIME` =
1e9 s"), read from the document and tried on a slave at both sides: a step ending on the
latest time is taken, one ending after it refused, a step below the shortest refused.  Tests
that import the constants agree with any value of them (training sample 4261's [6], 1e9 made
2e9, survived all of them but one)."""
from __future__ import annotations

import re

from fmus.slave import base
from tests.fmus.slave.test_extremes import slave_class
from tests.support.paths import ROOT

ROW = re.search(r"below `MIN_STEP` = (\S+) s, or ending after `MAX_TIME` = (\S+) s",
                (ROOT / "docs" / "extremes.md").read_text())
SHORTEST, LATEST = float(ROW.group(1)), float(ROW.group(2))


def _started_at(start):
    slave = slave_class("Trajectory")(instance_name="traj")
    slave.setup_experiment(start, None, None)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    return slave


def test_the_documented_bounds_are_the_codes():
    assert (base.MIN_STEP, base.MAX_TIME) == (SHORTEST, LATEST)


def test_a_step_ending_on_the_latest_time_is_taken_and_one_ending_after_it_refused():
    assert _started_at(LATEST - 1.0).do_step(LATEST - 1.0, 1.0)        # ends at 1e9 exactly
    late = _started_at(LATEST - 1.0)
    assert late.do_step(LATEST - 1.0, 2.0) is False
    assert f"ends after t = {LATEST:g} s" in late.error


def test_a_step_below_the_shortest_is_refused_naming_it():
    slave = _started_at(0.0)
    assert slave.do_step(0.0, SHORTEST / 2) is False
    assert f"is below the shortest step {SHORTEST:g} s" in slave.error
