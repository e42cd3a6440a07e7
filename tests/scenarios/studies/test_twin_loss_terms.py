"""The twin fit's loss pieces against docs/twin_method.md ("errors under 0.01 mm compared as
0.01 mm"; "ours are the means over the seeds") on made-up metrics
(scenarios/studies/twin_fit.py ``loss``, ``mean_metrics``, ``_spread``): the e_ss floor
applied to both sides at exactly its value, the seed means by hand, a stopped seed NaN
(issue 31: constants read back against the document, functions no test named)."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

from scenarios.batch.report import THESIS_BENCH
from scenarios.studies import twin_fit
from tests.support.paths import ROOT


def _thesis_means(kind="circle"):
    return {s: {"e_ef_mm": v[0], "tau_ef_Nm": v[1], "e_ss_mm": v[4]} for s, v in THESIS_BENCH[kind].items()}


def test_the_e_ss_floor_is_the_documents():
    """docs/twin_method.md states the floor in mm; the module's constant is that number."""
    text = (ROOT / "docs" / "twin_method.md").read_text()
    found = re.search(r"errors under ([0-9.]+) mm compared as ([0-9.]+) mm", text)
    assert found and found.group(1) == found.group(2)
    assert twin_fit.E_FLOOR_MM == float(found.group(1))


def test_an_e_ss_below_the_floor_counts_as_the_floor_and_one_above_does_not():
    """One strategy's e_ss (ours) at 0.001, 0.005 and exactly 0.01 mm gives one loss (all compared
    as 0.01 mm); at 0.02 mm another.  The e_ss term of a strategy whose bench value is under the
    floor is then ln(floor/floor) = 0.  Catches the floor not applied to ours, a floor of another
    value, and max turned into min."""
    s = next(s for s, m in _thesis_means().items() if m["e_ss_mm"] > 0.02)
    losses = []
    for value in (0.001, 0.005, twin_fit.E_FLOOR_MM, 0.02):
        means = _thesis_means()
        means[s]["e_ss_mm"] = value
        losses.append(twin_fit.loss(means))
    assert losses[0] == losses[1] == losses[2] != losses[3]
    # Against the bench's e_ss of that strategy: moving ours from the floor to 0.02 mm changes
    # the term by 0.5 (ln²(0.02/b) - ln²(0.01/b)), averaged over the 8 x 3 + 4 x 2 terms.
    b = THESIS_BENCH["circle"][s][4]
    change = twin_fit.E_SS_WEIGHT * (math.log(0.02 / b) ** 2 - math.log(0.01 / b) ** 2) / (8 * 3 + 4 * 2)
    assert losses[3] - losses[0] == pytest.approx(change, rel=1e-9)


def test_the_seed_means_are_numpys_and_a_stopped_seed_makes_them_nan():
    """Two seeds of made-up metrics: each strategy's metric is the mean over its seeds; a seed that
    did not complete makes its strategy's every metric NaN (the loss then infinite).  Catches
    the mean over strategies, a metric of another key, and a stopped run's numbers used."""
    runs = {"PDq": {101: {"e_ef_mm": 1.0, "tau_ef_Nm": 0.2, "e_ss_mm": 0.05, "completed": True},
                    102: {"e_ef_mm": 3.0, "tau_ef_Nm": 0.4, "e_ss_mm": 0.07, "completed": True}},
            "TCx": {101: {"e_ef_mm": 2.0, "tau_ef_Nm": 0.5, "e_ss_mm": 0.01, "completed": True},
                    102: {"e_ef_mm": 9.0, "tau_ef_Nm": 9.0, "e_ss_mm": 9.0, "completed": False}}}
    means = twin_fit.mean_metrics(runs)
    assert means["PDq"] == pytest.approx({"e_ef_mm": 2.0, "tau_ef_Nm": 0.3, "e_ss_mm": 0.06}, rel=1e-12)
    assert set(means["TCx"]) == set(twin_fit.METRICS) and all(math.isnan(v) for v in means["TCx"].values())


def test_the_spread_is_the_mean_the_least_and_the_largest_over_the_seeds():
    """Catches the spread's three numbers in another order or of another key."""
    by_seed = {s: {"e_ef_mm": v, "tau_ef_Nm": -v} for s, v in zip((101, 102, 103), (0.5, 2.0, 1.1))}
    assert twin_fit._spread(by_seed, "e_ef_mm") == pytest.approx((np.mean([0.5, 2.0, 1.1]), 0.5, 2.0), rel=1e-15)
    assert twin_fit._spread(by_seed, "tau_ef_Nm") == pytest.approx((-np.mean([0.5, 2.0, 1.1]), -2.0, -0.5), rel=1e-15)
