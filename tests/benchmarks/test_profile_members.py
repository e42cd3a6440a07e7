"""benchmarks/profile_members.py: its timed members step as the untimed ones and count every call."""
import sys
from dataclasses import replace
from types import SimpleNamespace

import pytest

from tests.support.paths import ROOT

sys.path.insert(0, str(ROOT / "benchmarks"))

import profile_members  # noqa: E402

from scenarios.scenes.catalogue import get_scene  # noqa: E402

STEPS = 300


@pytest.fixture(scope="module")
def timer(tmp_path_factory):
    return profile_members.timer_library(tmp_path_factory.mktemp("timer"))


def _scene():
    return SimpleNamespace(system=replace(get_scene("bench_circle_TCMDx").system, stop_time=STEPS * 1e-3))


def test_timed_members_give_the_untimed_rows_and_count_each_step(timer):
    """Catches a timing stand-in that skips or repeats a member's step (a call count other than
    one a step) or changes what it computes (the tool compares the timed run's rows with the
    untimed run's and stops)."""
    found = profile_members.profile(_scene(), timer, 1, profile_members.ticks_per_ns(timer, 0.01))
    assert len(found["names"]) == 8
    for ticks, calls, dropped in found["tallies"][0]:
        assert calls + dropped == STEPS and ticks > 0.0


def test_a_stand_in_that_does_not_step_is_caught(timer, monkeypatch):
    """Catches the rows check missing: members that do nothing in the timed run must stop the tool."""
    nothing = profile_members._address(timer, "pc_timed_nothing")
    real = profile_members._address
    monkeypatch.setattr(profile_members, "_address",
                        lambda lib, name: nothing if name == "pc_timed_io" else real(lib, name))
    with pytest.raises(RuntimeError, match="rows differ"):
        profile_members.profile(_scene(), timer, 1, profile_members.ticks_per_ns(timer, 0.01))
