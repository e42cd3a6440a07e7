"""The trade study's ratios and figure at a zero wall time or a zero deviation (issue 31,
training sweep s44: compare mutants at scenarios/studies/trade/measure.py:201-202 and
report.py:133).

speedup = defaults' wall / the row's wall and gain = defaults' deviation / the row's
deviation exist only for a positive denominator: a row timed at 0 s (below the clock's
resolution) or exactly the reference (deviation 0) has NaN there, not a division error; the
log-log figure leaves a zero-deviation row out (log 0) and plots the others.
"""
from __future__ import annotations

import math
from importlib import import_module

import matplotlib
import numpy as np

from scenarios.studies.trade import report
from scenarios.studies.trade.measure import Trade
from tests.scenarios.studies.test_trade_report import _row

matplotlib.use("Agg")
#: The module (the package exports a function of the same name).
measure = import_module("scenarios.studies.trade.measure")


def _bare(name, wall, err):
    return {"setting": name, "kind": "accuracy", "wall_s": wall, "rms_err_m": err, "error": ""}


def test_a_zero_wall_time_or_zero_deviation_has_no_ratio_and_the_others_have_theirs():
    """Deviations powers of two, so each ratio is exact."""
    rows = [_bare("defaults", 2.0, 2.0 ** -10), _bare("instant", 0.0, 2.0 ** -8), _bare("exact", 0.5, 0.0),
            _bare("tiny", 4.0, 2.0 ** -17)]
    measure._relative(rows)
    by = {r["setting"]: r for r in rows}
    assert math.isnan(by["instant"]["speedup"]) and by["instant"]["gain"] == 0.25
    assert by["exact"]["speedup"] == 4.0 and math.isnan(by["exact"]["gain"])
    assert by["tiny"]["speedup"] == 0.5 and by["tiny"]["gain"] == 128.0
    assert by["defaults"]["speedup"] == by["defaults"]["gain"] == 1.0


def test_the_figure_leaves_a_zero_deviation_row_out_and_plots_the_rest(tmp_path, monkeypatch):
    """A row exactly as the reference (deviation 0) among the accuracy rows: the dots are the
    other three, in order; the figure is written."""
    import matplotlib.pyplot as plt

    kept = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    rows = [_row("defaults", "accuracy", 2.0, 1.0, 1e-4, 1.0, True),
            _row("exact", "accuracy", 3.0, 0.67, 0.0, math.nan, False),
            _row("fast", "accuracy", 0.5, 4.0, 5e-4, 0.2, True),
            _row("precise", "accuracy", 4.0, 0.5, 5e-7, 200.0, True)]
    assert report.plot(Trade("bench_x", 1.5, rows, 12.3), tmp_path / "trade.png") == tmp_path / "trade.png"
    dots = np.asarray(kept[0].axes[0].collections[0].get_offsets())
    assert dots.tolist() == [[2.0, 1e-4], [0.5, 5e-4], [4.0, 5e-7]]
