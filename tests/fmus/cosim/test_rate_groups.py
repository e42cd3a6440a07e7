"""fmus/cosim/stepper.py's multi-rate groups (seed 3501's survivor [39], fmus/stepper.py:63 then):
consecutive plan entries of one sub-step count above 1 form one group, every other entry a
group of its own, whatever the position of the group in the plan."""
from __future__ import annotations

from fmus.cosim.stepper import Entry, rate_groups


def _plan(*counts):
    return [Entry(name, None, (f"{name}.in",), (0,), (f"{name}.out",), (1,), n) for name, n in zip("abcdefgh", counts)]


def _names(groups):
    return [(group.substeps, [entry.name for entry in group.entries]) for group in groups]


def test_equal_sub_step_counts_in_a_row_form_one_group_wherever_they_are():
    """Catches the member appended to another group than the last (``groups[1][-1]`` for
    ``groups[-1][1]``: the second group, or an IndexError with one group), single-rate entries
    merged, or groups of different counts merged."""
    assert _names(rate_groups(_plan(2, 2))) == [(2, ["a", "b"])]
    assert _names(rate_groups(_plan(1, 2, 2, 1, 3, 3, 3, 2))) == [
        (1, ["a"]), (2, ["b", "c"]), (1, ["d"]), (3, ["e", "f", "g"]), (2, ["h"])]
    assert _names(rate_groups(_plan(1, 1, 4, 2))) == [(1, ["a"]), (1, ["b"]), (4, ["c"]), (2, ["d"])]
    plan = _plan(1, 2, 2)
    assert rate_groups(plan)[1].entries == (plan[1], plan[2])
