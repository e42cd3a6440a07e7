"""scenarios/batch/sweep_plots.py's figure size as metrics (columns) are added: each panel keeps
its width in inches, as the rows keep their height (test_sweep_plots.py), and the columns are
drawn in the metrics' order (issue 31, training sample 4242: a figure size never read back)."""
from __future__ import annotations

import matplotlib
import pytest

from scenarios.batch import sweep_plots
from tests.scenarios.batch.test_sweep_plots import _rows, kept  # noqa: F401 (the fixture)

matplotlib.use("Agg")


def test_each_column_of_panels_keeps_its_width_and_order_as_metrics_are_added(kept, tmp_path):  # noqa: F811
    """Catches a figure of fixed width (its columns squashed as metrics are added) and columns
    drawn out of the metrics' order: the panels of a three-metric figure are as wide, in inches,
    as the panel of a one-metric figure, and left to right in the order given."""
    groups = {"A": _rows([1.0, 2.0, 3.0]), "B": _rows([2.0, 4.0])}

    def widths(fig):
        return [ax.get_position().width * fig.get_size_inches()[0] for ax in fig.axes]

    sweep_plots.plot_groups({"p": groups}, tmp_path / "one.png", metrics=("e_ef_mm",))
    metrics = ("e_ef_mm", "tau_ef_Nm", "e_ss_mm")
    sweep_plots.plot_groups({"p": groups}, tmp_path / "three.png", metrics=metrics)
    one, three = kept
    assert len(one.axes) == 1 and len(three.axes) == 3
    assert widths(three) == pytest.approx([widths(one)[0]] * 3, rel=0.15)
    assert [ax.get_title() for ax in three.axes] == [f"p: {sweep_plots._LABELS[m]}" for m in metrics]
    assert [ax.get_position().x0 for ax in three.axes] == sorted(ax.get_position().x0 for ax in three.axes)
