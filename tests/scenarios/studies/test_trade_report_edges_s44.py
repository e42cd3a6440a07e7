"""The trade figure at the edge of its log axes (issue 31, session 44: boundaries of the
generalised training sample): a row whose deviation is exactly 0 (a setting identical to the
reference) has no place on a log axis and is left out; the smallest positive one is plotted."""
from __future__ import annotations

import matplotlib
import numpy as np

from scenarios.studies.trade import report
from scenarios.studies.trade.measure import Trade

matplotlib.use("Agg")


def _row(setting, wall, rms, pareto):
    return {"setting": setting, "kind": "accuracy", "what": setting, "wall_s": wall, "cpu_s": wall,
            "speedup": 1.0, "rms_err_m": rms, "max_err_m": rms, "gain": 1.0, "residual_m": 0.0,
            "current_err_A": 0.0, "energy_err": 0.0, "enc_diff": 0, "enc_first_s": 0.0, "e_ef_mm": 0.5,
            "pareto": pareto, "error": ""}


def test_a_row_with_zero_deviation_is_left_out_of_the_figure_and_a_tiny_one_is_in(tmp_path, monkeypatch):
    """Catches ``>=`` for ``>`` on the deviation (log10(0): the figure fails or plots -inf)."""
    import matplotlib.pyplot as plt

    kept = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    rows = [_row("defaults", 2.0, 1e-4, True), _row("same", 1.0, 0.0, False), _row("tiny", 3.0, 1e-300, True)]
    assert report.plot(Trade("bench_x", 1.5, rows, 1.0), tmp_path / "t.png") == tmp_path / "t.png"
    dots = np.asarray(kept[0].axes[0].collections[0].get_offsets())
    assert dots.tolist() == [[2.0, 1e-4], [3.0, 1e-300]]
