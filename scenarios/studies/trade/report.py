"""The trade study's report: ``trade.csv`` (and ``noquant.csv``), ``trade.md`` and ``trade.png``
(columns in the package doc, :mod:`scenarios.studies.trade`)."""
from __future__ import annotations

import csv
import math
from pathlib import Path

from scenarios.studies.trade.measure import FINE_ENCODER, REPEAT_BELOW_S, WALL_TOLERANCE, Trade

COLUMNS = ("setting", "kind", "what", "wall_s", "cpu_s", "speedup", "rms_err_m", "max_err_m", "gain", "residual_m",
           "current_err_A", "energy_err", "enc_diff", "enc_first_s", "e_ef_mm", "pareto", "error")


def _fmt(key, value) -> str:
    if isinstance(value, bool):
        return "yes" if value else ""
    if isinstance(value, float):
        if not math.isfinite(value):
            return ""
        if key in ("wall_s", "cpu_s", "speedup", "gain", "e_ef_mm", "enc_first_s"):
            return f"{value:.4g}"
        return f"{value:.3e}"
    return str(value)


def write_csv(path: Path, rows: list) -> Path:
    """One row per setting, the :data:`COLUMNS`."""
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        for r in rows:
            writer.writerow([_fmt(k, r.get(k, "")) for k in COLUMNS])
    return path


def _md_value(key, value) -> str:
    text = _fmt(key, value)
    if not text:
        return "–" if key != "pareto" else ""
    if key in ("rms_err_m", "max_err_m", "residual_m", "current_err_A", "energy_err"):
        return f"{value:.2g}" if key != "energy_err" else f"{value:+.2g}"
    if key == "speedup":
        return f"{value:.2f}×"
    if key == "gain":
        return f"{value:.2g}×"
    if key in ("wall_s", "cpu_s"):
        return f"{value:.2f}"
    if key == "e_ef_mm":
        return f"{value:.3f}"
    if key == "enc_first_s":
        return f"{value:.3f}"
    if key == "pareto":
        return "**front**"
    return text.replace("|", "\\|")


_MD_COLUMNS = (("setting", "setting"), ("kind", "kind"), ("wall_s", "wall [s]"), ("cpu_s", "CPU [s]"),
               ("speedup", "speed-up"),
               ("rms_err_m", "RMS dev. [m]"), ("max_err_m", "max dev. [m]"), ("gain", "RMS gain"),
               ("residual_m", "residual [m]"), ("current_err_A", "current dev. [A]"),
               ("energy_err", "energy dev."), ("enc_diff", "enc. diff"), ("enc_first_s", "first diff [s]"),
               ("e_ef_mm", "e_ef [mm]"),
               ("pareto", "front"))


def markdown_table(rows: list) -> str:
    """The rows as a markdown table (errors of stopped runs below it)."""
    lines = ["| " + " | ".join(h for _, h in _MD_COLUMNS) + " |",
             "|" + "|".join("---" for _ in _MD_COLUMNS) + "|"]
    for r in rows:
        lines.append("| " + " | ".join(_md_value(k, r.get(k, "")) for k, _ in _MD_COLUMNS) + " |")
    stopped = [f"* {r['setting']}: {r['error']}" for r in rows if r.get("error")]
    if stopped:
        lines += ["", "Runs that stopped:", ""] + stopped
    return "\n".join(lines)


def render(trade: Trade, command: str) -> str:
    """``trade.md``: what was run, the table, the front and the extremes."""
    rows = trade.rows
    base = next((r for r in rows if r["setting"] == "defaults"), None)
    out = [f"# Speed against accuracy: {trade.scene}, 0–{trade.stop_time:g} s", "",
           f"`{command}`", "",
           f"Truth: one monolithic reference run of the unmodified scene ({trade.reference_wall_s:.1f} s wall). "
           "`accuracy` rows compute the same model differently: their deviation is an error. `fidelity` rows "
           "change the model: their deviation is what the effect changes in the result. Wall time: "
           f"the whole `simulate` call (loading, initialisation, stepping), best of {trade.rounds} interleaved round(s) (runs over "
           f"{REPEAT_BELOW_S:g} s: one); CPU: the process's CPU time over the same call.", ""]
    out.append(markdown_table(rows))
    out += ["", "Settings:", ""] + [f"* **{r['setting']}** ({r['kind']}): {r['what']}" for r in rows] + [""]
    front = [r["setting"] for r in rows if r.get("pareto")]
    out.append("Pareto front (accuracy rows, wall time against RMS deviation; wall times within "
               f"{100 * WALL_TOLERANCE:g} % count as equal): " + ", ".join(front) + ".")
    if base is not None and not base["error"]:
        fast = [r for r in rows if not r["error"] and r["speedup"] >= 3.0]
        accurate = [r for r in rows if not r["error"] and r["kind"] == "accuracy" and r["gain"] >= 100.0]
        best = max((r for r in rows if not r["error"] and r["kind"] == "accuracy"),
                   key=lambda r: r["gain"], default=None)
        out.append("")
        out.append(f"Defaults: {base['wall_s']:.2f} s wall, RMS deviation {base['rms_err_m']:.2g} m, "
                   f"max {base['max_err_m']:.2g} m.")
        out.append("At least 3× faster: " + (", ".join(f"{r['setting']} ({r['speedup']:.1f}×, {r['kind']}, "
                                                    f"RMS {r['rms_err_m']:.2g} m)" for r in fast) or "none") + ".")
        out.append("At least 100× more accurate: " + (", ".join(f"{r['setting']} ({r['gain']:.0f}×, "
                                                          f"{r['speedup']:.2f}× the speed)" for r in accurate)
                                                    or "none") + "."
                   + (f" Most accurate: {best['setting']}, {best['gain']:.2g}× at {best['speedup']:.2f}× the speed."
                      if best is not None else ""))
    if trade.skipped:
        out += ["", "Not applicable to this scene: " + ", ".join(trade.skipped) + "."]
    if trade.noquant:
        out += ["", f"## Without encoder quantisation ({FINE_ENCODER} counts per revolution, reference and runs)",
                "", markdown_table(trade.noquant)]
    out += ["", "![wall time against deviation](trade.png)", ""]
    return "\n".join(out)


def plot(trade: Trade, path: Path) -> Path:
    """Log-log wall time against RMS deviation: accuracy rows (front joined), fidelity rows marked x.

    Labels that would overlap another are left out (every point is a row of the table)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [("against the reference", trade.rows)]
    if trade.noquant:
        panels.append(("encoder quantisation removed", trade.noquant))
    fig, axes = plt.subplots(1, len(panels), figsize=(7.5 * len(panels), 6), squeeze=False)
    for ax, (title, rows) in zip(axes[0], panels):
        ok = [r for r in rows if not r["error"] and r["rms_err_m"] > 0 and math.isfinite(r["rms_err_m"])]
        acc = [r for r in ok if r["kind"] == "accuracy"]
        fid = [r for r in ok if r["kind"] == "fidelity"]
        front = sorted([r for r in acc if r.get("pareto")], key=lambda r: r["wall_s"])
        ax.scatter([r["wall_s"] for r in acc], [r["rms_err_m"] for r in acc], marker="o", color="C0",
                   label="accuracy setting (deviation = error)", zorder=3)
        if fid:
            ax.scatter([r["wall_s"] for r in fid], [r["rms_err_m"] for r in fid], marker="x", color="C3",
                       label="fidelity switch (deviation = change)", zorder=3)
        if front:
            ax.step([r["wall_s"] for r in front], [r["rms_err_m"] for r in front], where="post", color="C0",
                    lw=1, alpha=0.7, label="Pareto front")
        base = [r for r in ok if r["setting"] == "defaults"]
        if base:
            ax.scatter([base[0]["wall_s"]], [base[0]["rms_err_m"]], marker="*", s=160, color="k", zorder=4,
                       label="defaults")
        # Labels: defaults, the front, then the rest, leaving out those whose box (in log10
        # units, from the label's length and the axes' spans) would overlap a placed one.
        xs = [math.log10(r["wall_s"]) for r in ok]
        ys = [math.log10(r["rms_err_m"]) for r in ok]
        span_x = max(max(xs) - min(xs), 0.5) * 1.1
        span_y = max(max(ys) - min(ys), 0.5) * 1.1
        char_w, line_h = 0.0105 * span_x, 0.03 * span_y     # fontsize 7 on a 7.5 x 6 in panel
        placed = []
        for r in sorted(ok, key=lambda r: (r["setting"] != "defaults", not r.get("pareto"), r["wall_s"])):
            x, y = math.log10(r["wall_s"]), math.log10(r["rms_err_m"])
            box = (x, x + char_w * len(r["setting"]), y, y + line_h)
            if any(box[0] < b[1] and b[0] < box[1] and box[2] < b[3] and b[2] < box[3] for b in placed):
                continue
            placed.append(box)
            ax.annotate(r["setting"], (r["wall_s"], r["rms_err_m"]), fontsize=7, xytext=(4, 2),
                        textcoords="offset points")
        ax.axhline(1e-5, color="0.5", ls=":", lw=1, label="1e-5 m")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set(xlabel="wall time [s]", ylabel="RMS end-effector deviation from the reference [m]",
               title=f"{trade.scene}, 0–{trade.stop_time:g} s: {title}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, loc="lower left" if rows is trade.rows else "best")   # the fast, inaccurate corner is empty
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path
