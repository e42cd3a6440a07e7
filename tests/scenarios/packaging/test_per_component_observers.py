"""scenarios/packaging/per_component.py's pure parts on the bench scene and systems changed
here: the observers folded into their drives (and each refusal, word for word), the sub-step
count asked for or chosen (and refused), the multi-rate refusal (issue 31: every branch of a
transform, error messages naming variable and value)."""
from __future__ import annotations

from dataclasses import replace

import pytest

from fmus.cosim.system import Component, Connection
from scenarios.packaging.per_component import (SUBSTEP_CHOICES, choose_substeps, feedback_delays,
                                               per_component_system, with_internal_observers)
from scenarios.scenes import get_scene

BENCH = get_scene("bench_circle_TCMDx").system


def _observer(system, name, **parameters):
    return replace(system, components=tuple(replace(c, parameters={**c.parameters, **parameters}) if c.name == name
                                            else c for c in system.components))


def test_each_observer_moves_into_the_drive_it_feeds_and_its_wiring_goes():
    """obs1 feeds drive1, obs2 drive2 (kind given to obs2 only): the observers, their
    connections and recorded signals go; each drive gets ``internal_observer`` (and obs2's kind
    as ``observer_kind``), nothing else changes; a system without observers is returned as it is.
    Catches an observer folded into the wrong drive, a kind lost or given to both, a connection
    or record of an observer kept, another component changed."""
    system = _observer(BENCH, "obs2", kind="reduced")
    folded = with_internal_observers(system)
    names = [c.name for c in system.components if c.model != "CurrentObserver"]
    assert [c.name for c in folded.components] == names
    for c, before in zip(folded.components, (c for c in system.components if c.model != "CurrentObserver")):
        extra = {"drive1": {"internal_observer": True},
                 "drive2": {"internal_observer": True, "observer_kind": "reduced"}}.get(c.name, {})
        assert c.parameters == {**before.parameters, **extra} and c.model == before.model, c.name
    assert folded.connections == tuple(c for c in system.connections
                                       if not c.source.startswith("obs") and not c.target.startswith("obs"))
    assert folded.record == tuple(s for s in system.record if not s.startswith("obs"))
    assert len(folded.connections) == len(system.connections) - 6
    assert (folded.step, folded.stop_time) == (system.step, system.stop_time)
    assert with_internal_observers(folded) is folded


def test_an_observer_that_cannot_move_into_a_drive_is_refused_naming_it():
    """One that feeds no drive's i_hat, one of another motor than its drive's, one with a
    parameter other than preset and kind.  Catches each check skipped or naming the other
    party."""
    unfed = replace(BENCH, connections=tuple(c for c in BENCH.connections if c.source != "obs2.i_hat"))
    with pytest.raises(ValueError) as refusal:
        with_internal_observers(unfed)
    assert str(refusal.value) == "observer obs2 feeds no drive's i_hat: it cannot move into a drive"
    elsewhere = replace(BENCH, connections=tuple(Connection("obs2.i_hat", "drive2.v_ref") if c.source == "obs2.i_hat"
                                                 else c for c in BENCH.connections))
    with pytest.raises(ValueError, match="^observer obs2 feeds no drive's i_hat: it cannot move into a drive$"):
        with_internal_observers(elsewhere)       # its estimate wired to another input of the drive
    with pytest.raises(ValueError) as refusal:
        with_internal_observers(_observer(BENCH, "obs1", preset="motor2"))
    assert str(refusal.value) == ("observer obs1 (preset 'motor2') and drive drive1 (preset 'motor1'): an internal "
                                  "observer uses its drive's motor")
    with pytest.raises(ValueError) as refusal:
        with_internal_observers(_observer(BENCH, "obs2", R=1.5, L=1e-3, kind="full"))
    assert str(refusal.value) == ("observer obs2 sets L, R: an internal observer takes its drive's motor and only "
                                  "the parameter kind (as observer_kind)")


@pytest.mark.parametrize("last_stage, n", [(0, SUBSTEP_CHOICES[0]), (3, 4), (4, 5), (SUBSTEP_CHOICES[-1] - 1,
                                                                                      SUBSTEP_CHOICES[-1])])
def test_the_sub_steps_chosen_are_the_fewest_that_hold_the_stages(last_stage, n):
    """Catches a choice that holds one stage fewer or the next larger."""
    assert choose_substeps(last_stage) == n
    assert all(c < last_stage + 1 for c in SUBSTEP_CHOICES if c < n)


def test_sub_steps_asked_for_are_taken_whole_and_others_refused():
    """Any whole n >= 1 asked for is taken, below the stages too; a fraction, 0, a bool are refused
    naming the value; a chain longer than the largest choice is refused naming its stages.
    Catches the request overridden by the choice, 0 or True taken."""
    assert choose_substeps(3, 1) == 1 and choose_substeps(0, 7) == 7 and choose_substeps(2, 3.0) == 3
    for bad in (0, 2.5, True, -1):
        with pytest.raises(ValueError) as refusal:
            choose_substeps(1, bad)
        assert str(refusal.value) == f"substeps = {bad!r} must be a whole number >= 1"
    with pytest.raises(ValueError) as refusal:
        choose_substeps(SUBSTEP_CHOICES[-1])
    assert str(refusal.value) == (f"a chain of {SUBSTEP_CHOICES[-1] + 1} sampled stages needs more than "
                                  f"{SUBSTEP_CHOICES[-1]} sub-steps")


def test_a_multi_rate_system_is_refused_and_an_open_loop_has_no_feedback_delay():
    """A component with sub-steps cannot be exported per component; a controller whose angles
    come through no closed path (its q1 fed by the trajectory) has no feedback delay.  Catches
    the multi-rate check skipped, a delay counted along a path that does not close."""
    multi = replace(BENCH, components=tuple(replace(c, substeps=2) if c.name == "plant" else c
                                            for c in BENCH.components))
    with pytest.raises(ValueError, match=r"^multi-rate components \(substeps > 1\) cannot be exported per component$"):
        per_component_system(multi, {})
    assert feedback_delays(BENCH, "ctrl") == (2, 3)
    rewired = replace(BENCH, connections=tuple(Connection("traj.x_d", c.target) if c.target == "ctrl.q1" else c
                                               for c in BENCH.connections))
    assert feedback_delays(rewired, "ctrl") == (0, 0)
    open_rates = replace(BENCH, connections=tuple(Connection("traj.dx_d", c.target) if c.target == "ctrl.dq1" else c
                                                  for c in BENCH.connections))
    assert feedback_delays(open_rates, "ctrl") == (0, 0)      # the angles' path closes, the rates' does not
    alone = replace(BENCH, components=BENCH.components + (Component("spare", "Derivator", {}),))
    assert feedback_delays(alone, "spare") == (0, 0)


def test_a_scene_without_a_start_position_has_no_floor_and_runs_nothing(monkeypatch):
    """reproducibility of the wheeled pendulum's scene (no component with ``x0`` to shift): 0.0,
    without a run.  Catches the floor measured by shifting a parameter the scene lacks."""
    from fmus.cosim import master
    from scenarios.packaging.per_component import reproducibility

    monkeypatch.setattr(master, "simulate", lambda *args, **kwargs: pytest.fail("nothing is run"))
    assert reproducibility(get_scene("pendulum_balance")) == 0.0
