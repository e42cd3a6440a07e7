"""Violin and box plots of sweeps (matplotlib only here, as the rest of scenarios/ stays plot-free).

:func:`plot_sweep`: one sweep's metrics; :func:`plot_groups`: several sweeps side by side
(the strategies of the robustness study, docs/sweeps.md).
"""
from __future__ import annotations

import math
from pathlib import Path

_LABELS = {"e_ef_mm": "e_ef [mm]", "tau_ef_Nm": "τ_ef [N m]", "e_ss_mm": "e_ss [mm]"}


def _finite(rows, metric) -> list:
    return [r[metric] for r in rows if r["completed"] and math.isfinite(r[metric])]


def _violins(ax, groups: dict, metric: str) -> None:
    """Violins (the distribution) with box plots inside (median, quartiles, 5-95 % whiskers); the
    groups' names as tick labels, slanted by 30° when there are more than four."""
    labels = list(groups)
    data = [_finite(groups[k], metric) for k in labels]
    positions = [i for i, d in enumerate(data) if len(d) > 1]
    if positions:
        ax.violinplot([data[i] for i in positions], positions=positions, showextrema=False, widths=0.8)
    filled = [i for i, d in enumerate(data) if d]
    if filled:
        ax.boxplot([data[i] for i in filled], positions=filled, widths=0.25, whis=(5, 95), showfliers=False)
    ax.set_xticks(range(len(labels)), labels, fontsize=8, rotation=30 if len(labels) > 4 else 0)
    ax.set_ylabel(_LABELS[metric])
    ax.grid(True, axis="y", alpha=0.3)


def plot_sweep(sweep, path: Path) -> Path:
    """sweep.png: e_ef, τ_ef and e_ss of one sweep."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(10, 3.8))
    for ax, metric in zip(axes, _LABELS):
        _violins(ax, {sweep.scene: sweep.rows}, metric)
    st = sweep.settings
    fig.suptitle(f"{sweep.scene}: {len(sweep.rows)} samples, U = {st['uncertainty']:g} ({st['distribution']}), "
                 f"seed {st['seed']}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_groups(panels: dict, path: Path, metrics=("e_ef_mm", "tau_ef_Nm"), log=("e_ef_mm",)) -> Path:
    """One row of panels per key of ``panels`` (title -> {label: rows}), one column per metric."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(panels), len(metrics), figsize=(5.5 * len(metrics), 3.2 * len(panels)),
                             squeeze=False)
    for row, (title, groups) in enumerate(panels.items()):
        for col, metric in enumerate(metrics):
            ax = axes[row, col]
            _violins(ax, groups, metric)
            if metric in log:
                ax.set_yscale("log")
            ax.set_title(f"{title}: {_LABELS[metric]}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
