"""The trade study's command: :func:`run_trade` (``parcosim trade``) sweeps the settings
(:mod:`scenarios.studies.trade.settings`), measures them (:mod:`scenarios.studies.trade.measure`)
and writes the report (:mod:`scenarios.studies.trade.report`)."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from scenarios.reference import reference_run
from scenarios.scenes.catalogue import get_scene
from scenarios.studies.trade.measure import Trade, _noquant, _relative, _sweep
from scenarios.studies.trade.report import plot, render, write_csv
from scenarios.studies.trade.settings import settings

DEFAULT_SCENE = "bench_circle_TCMDx"
#: Simulated time of the quick sweep [s].
QUICK_STOP_TIME = 1.0
#: Timing rounds (each round runs every setting once, interleaved; the best round counts).
FULL_ROUNDS = 5
QUICK_ROUNDS = 1


def run_trade(scene=DEFAULT_SCENE, quick: bool = False, out_dir=None, stop_time: float | None = None,
              rounds: int | None = None, progress=None) -> Trade:
    """Sweep the settings of ``scene`` (a name or a :class:`Scene`) and write the report.

    Parameters
    ----------
    quick : bool
        A shorter run (:data:`QUICK_STOP_TIME`) over fewer settings, one timing round and no
        no-quantisation study: under a minute on the bench scene.
    out_dir : path, optional
        Where ``trade.csv``, ``trade.md`` and ``trade.png`` (and ``noquant.csv``) go.
    stop_time : float, optional
        Simulated time (default: the scene's, or :data:`QUICK_STOP_TIME` with ``quick``).
    rounds : int, optional
        Timing rounds (default :data:`QUICK_ROUNDS` quick, :data:`FULL_ROUNDS` full).
    progress : callable, optional
        Called with one line of text per step of the sweep.
    """
    say = progress or (lambda line: None)
    base = get_scene(scene) if isinstance(scene, str) else scene
    stop = stop_time if stop_time is not None else (QUICK_STOP_TIME if quick else base.system.stop_time)
    stop = min(float(stop), base.system.stop_time)
    base = replace(base, system=replace(base.system, stop_time=stop))
    rounds = rounds if rounds is not None else (QUICK_ROUNDS if quick else FULL_ROUNDS)
    chosen = settings(quick)
    say(f"{base.name}, 0-{stop:g} s: reference ...")
    reference = reference_run(base)
    if not reference.completed:
        raise RuntimeError(f"the reference of {base.name} stopped: {reference.error}")
    say(f"reference: {reference.wall_s:.1f} s wall; the settings ...")
    rows, skipped = _sweep(base, chosen, reference, rounds, say)
    _relative(rows)
    trade = Trade(base.name, stop, rows, reference.wall_s, rounds=rounds, skipped=skipped)
    if not quick:
        trade.noquant = _noquant(base, rounds, say)
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        command = f"parcosim trade {base.name}" + (" --quick" if quick else "") + f" --out {out_dir}"
        trade.files.append(write_csv(out / "trade.csv", rows))
        if trade.noquant:
            trade.files.append(write_csv(out / "noquant.csv", trade.noquant))
        trade.files.append(plot(trade, out / "trade.png"))
        (out / "trade.md").write_text(render(trade, command))
        trade.files.append(out / "trade.md")
    return trade
