"""scenarios/batch/report.py's report.png: ours and the thesis' bar of each strategy stand side
by side, each 0.4 wide, ours left of the strategy's tick and the thesis' right of it, touching
and not overlapping (issue 31, training sample 4242: the bars' geometry never read back;
test_report_files.py reads back their heights)."""
from __future__ import annotations

import matplotlib
import pytest

from scenarios.batch import report
from scenarios.batch.report import KINDS, THESIS_BENCH
from tests.scenarios.batch.test_report_files import _made_up

matplotlib.use("Agg")


def test_ours_and_the_thesis_bars_stand_side_by_side_at_each_strategys_tick(tmp_path, monkeypatch):
    """Catches a bar of the default width (0.8: ours covering the thesis' bar), the two bars
    on the same side of the tick, and a tick not between its two bars."""
    import matplotlib.pyplot as plt

    kept, close = [], plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    report.plot_report(_made_up(), tmp_path / "report.png")
    axes = kept[0].axes
    for col, kind in enumerate(KINDS):
        n = len(THESIS_BENCH[kind])
        for row in range(2):
            ax = axes[2 * row + col]
            spans = [(p.get_x(), p.get_x() + p.get_width()) for p in ax.patches]
            ours, thesis = spans[:n], spans[n:]
            assert len(thesis) == n
            for k, tick in enumerate(ax.get_xticks()):
                assert tick == k
                assert ours[k] == pytest.approx((k - 0.4, k)), (kind, row, k)
                assert thesis[k] == pytest.approx((k, k + 0.4)), (kind, row, k)
