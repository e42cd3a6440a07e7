"""The twin report's "lower in twin, every seed" column at a tie (issue 31, session 44: boundaries
of the generalised training sample): a seed on which the sliding-mode strategy's e_ef equals the
pure one's is not a seed it lowers."""
from __future__ import annotations

from scenarios.studies import twin_fit
from tests.scenarios.studies.test_twin_report import SEEDS, _runs


def test_a_seed_where_the_md_term_ties_is_not_lowered_and_the_pair_says_no():
    """PDx -> PDMDx on the triangle: lower on two seeds, exactly equal on the third: 'no'; a float
    lower on that seed too: 'yes'.  Catches ``<=`` for ``<``."""
    runs = _runs()
    for kind in runs:
        for s in twin_fit.ORDER:
            for m in runs[kind][s].values():
                m.update(settled=True, e_contour_sides_mm=[0.1, 0.2, 0.3])
    pure, md = runs["triangle"]["PDx"], runs["triangle"]["PDMDx"]
    assert all(md[seed]["e_ef_mm"] < pure[seed]["e_ef_mm"] for seed in SEEDS)
    fit = {"loss": 0.25, "start_loss": 1.5, "evaluations": 7, "seeds": [1]}

    def verdict():
        lines = twin_fit.render(runs, twin_fit.START, fit).splitlines()
        triangle = lines.index("## Triangle: predicted without refitting (Tables 10, 14)")
        [row] = [line for line in lines[triangle:] if line.startswith("| PDx → PDMDx |")]
        return row.rsplit("|", 2)[1].strip()

    assert verdict() == "yes"
    md[SEEDS[2]]["e_ef_mm"] = pure[SEEDS[2]]["e_ef_mm"]
    assert verdict() == "no"
