"""The work limit's constants as docs/plant.md "The work of one call" states them (issue 31,
session 44: the tests of fmus/slave/budget.py compute their expectations from the module's own
constants, so a unit cost or the call's CPU changed passed them all).

The table there gives, per unit of work, the cost charged and how many units one call may take;
both are read here and compared with :func:`fmus.slave.budget.plant_evaluation_cost`, the
module's constants and :func:`fmus.slave.budget.per_call`.  The refusal the section quotes for
RK4 substeps over the limit is then produced word for word.
"""
from __future__ import annotations

import re

import pytest

from fmus.slave import budget
from tests.fmus.slave.test_extremes import make_slave
from tests.support.paths import ROOT

SECTION = (ROOT / "docs" / "plant.md").read_text(encoding="utf-8").split("\n## The work of one call\n", 1)[1] \
    .split("\n## ", 1)[0]
UNITS = {"µs": 1e-6, "ms": 1e-3}


def _rows() -> list:
    """(charged cost [s], units per call) of each row of the section's table, in order."""
    rows = []
    for line in SECTION.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 4 or not cells[0].startswith(("right-hand side", "inner")):
            continue
        value, unit = re.search(r"([\d.]+) (µs|ms)$", cells[2]).groups()
        rows.append((float(value) * UNITS[unit], int(cells[3].replace(" ", ""))))
    return rows


#: The unit of each row of the table, in its order (the row's own words say which).
COSTS = [
    lambda: budget.plant_evaluation_cost("fast", "rk4", 4),
    lambda: budget.plant_evaluation_cost("fast", "dopri5", 4),
    lambda: budget.plant_evaluation_cost("general", "rk4", 4),
    lambda: budget.plant_evaluation_cost("general", "rk4", 9),
    lambda: budget.WHEELED_RK4_EVALUATION,
    lambda: budget.INNER_STEP,
]


def test_the_call_may_spend_one_second():
    assert "`CALL_CPU_SECONDS` = 1 s" in SECTION.replace("\n", " ")
    assert budget.CALL_CPU_SECONDS == 1.0


@pytest.mark.parametrize("row", range(len(COSTS)))
def test_each_unit_is_charged_its_documented_cost_and_a_call_takes_the_documented_count(row):
    """Catches a unit cost (or the general algorithm's base or per-joint part) off the table's
    'charged' column, and the count per call computed otherwise than floor(1 s / cost)."""
    rows = _rows()
    assert len(rows) == len(COSTS)
    charged, count = rows[row]
    assert COSTS[row]() == pytest.approx(charged, rel=1e-12)
    assert budget.per_call(COSTS[row]()) == count


def test_the_general_algorithms_cost_is_its_base_plus_a_share_per_joint_as_documented():
    """'1.0 ms + 0.25 ms a joint': the same for either integrator, and for 4 and 9 joints."""
    base, per_joint = (float(v) * 1e-3 for v in re.search(r"([\d.]+) ms \+ ([\d.]+) ms a joint", SECTION).groups())
    for method in ("rk4", "dopri5"):
        for joints in (4, 9):
            assert budget.plant_evaluation_cost("general", method, joints) == pytest.approx(base + joints * per_joint,
                                                                                          rel=1e-12)


def test_the_quoted_rk4_refusal_is_the_slaves_word_for_word():
    """The section's example: a general-kernel FiveBarPlant with 10000 substeps is refused at
    initialisation, naming its 40000 evaluations, the 500 a call may take and substeps <= 125."""
    quoted = re.search(r'\("(parameters kernel = .*?)"', SECTION.replace("\n  ", " "), re.S).group(1)
    slave = make_slave("FiveBarPlant", {"kernel": "general", "substeps": 10000})
    assert slave.error == f"initialisation refused: {quoted} (t = 0 s)"


@pytest.mark.parametrize("seconds, text", [(1e-3, "1 ms"), (2e-3, "2 ms"), (3.25e-3, "3.2 ms"), (40e-6, "40 µs"),
                                           (1.5e-6, "1.5 µs"), (0.1e-6, "0.1 µs")])
def test_a_unit_cost_is_written_in_ms_from_one_millisecond_and_in_us_below(seconds, text):
    """The unit costs in the refusals ('(~2 ms each)', '(~16 µs each)' in the section): one
    millisecond itself is '1 ms' (the switch's boundary), two significant digits."""
    assert budget.short(seconds) == text
