"""The trade study's measurement: each setting run and timed (interleaved rounds, the best
counts), its deviation from the monolithic reference, the Pareto front, and the coupling
settings against a reference without encoder quantisation (package doc,
:mod:`scenarios.studies.trade`)."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from fmus.cosim.master import simulate
from fmus.cosim.system import System
from scenarios.reference import common_rows, deviation, encoder_differences, reference_run
from scenarios.run.metrics import rms_norm, scene_metrics
from scenarios.scenes.scene import Scene
from scenarios.studies.trade.settings import Setting, _change, _drives, _group, _in_plant, _plant, _unchanged

#: Settings whose first run takes longer than this are not repeated [s].
REPEAT_BELOW_S = 5.0
#: Each setting runs this long once before it is timed [s].
WARM_UP_S = 0.02
#: Wall times within this fraction of each other count as equally fast on the front.
WALL_TOLERANCE = 0.10
#: Encoder counts that make the quantisation negligible (the no-quantisation study).
FINE_ENCODER = 2 ** 30


@dataclass
class Trade:
    """What :func:`scenarios.studies.trade.study.run_trade` measured and wrote."""

    scene: str
    stop_time: float
    rows: list
    reference_wall_s: float
    rounds: int = 1
    files: list = field(default_factory=list)
    noquant: list = field(default_factory=list)
    skipped: list = field(default_factory=list)

    def row(self, setting: str) -> dict:
        """The row of ``setting``."""
        for r in self.rows:
            if r["setting"] == setting:
                return r
        raise KeyError(setting)


def _with_record(system: System, plant: str | None, columns: dict) -> System:
    extra = list(columns.values())
    if plant is not None:
        extra += [f"{plant}.{s}" for s in ("x", "y", "q1_enc", "q2_enc", "residual")]
    return replace(system, record=tuple(dict.fromkeys(tuple(system.record) + tuple(extra))))


#: The scene columns of the drives' currents and voltages.
ELECTRICAL_COLUMNS = ("i1", "i2", "v1", "v2")


def _electrical(get) -> dict | None:
    """Columns i1, i2, v1, v2 through ``get(column)`` (None when one is missing)."""
    try:
        return {c: np.asarray(get(c)) for c in ELECTRICAL_COLUMNS}
    except KeyError:
        return None


def _energy(e: dict, time: np.ndarray) -> float:
    """Electrical energy the drives draw over ``time``, ∫ (v1 i1 + v2 i2) dt (v held over each
    interval, i trapezoidal)."""
    total = 0.0
    dt = np.diff(time)
    for j in ("1", "2"):
        i, v = e[f"i{j}"], e[f"v{j}"]
        total += float(np.sum(dt * v[1:] * 0.5 * (i[1:] + i[:-1])))
    return total


def measure(result, reference, scene: Scene) -> dict:
    """The error columns of one run against the reference (empty where they do not apply).

    Rows at common times are compared (:func:`scenarios.reference.common_rows`: a run at a
    longer step meets every k-th reference row).  Currents compare the scene columns
    ``i1, i2`` (wherever the scene computes them: drives or the actuated plant) with the
    reference's; the energy error is that of each run's own ∫ (v1 i1 + v2 i2) dt."""
    plant = _plant(scene)
    ia, ib = common_rows(result.time, reference.time)
    d = deviation(result, reference)
    row = {"rms_err_m": d["rms"], "max_err_m": d["max"], "residual_m": float("nan"),
           "current_err_A": float("nan"), "energy_err": float("nan"), "enc_diff": "", "enc_first_s": float("nan")}
    if plant is not None and f"{plant}.residual" in result.signals:
        row["residual_m"] = float(np.max(np.abs(result[f"{plant}.residual"])))
    ours = _electrical(lambda c: result[scene.columns[c]])
    theirs = _electrical(lambda c: reference.columns[c])
    if ours is not None and theirs is not None:
        row["current_err_A"] = rms_norm(ours["i1"][ia] - theirs["i1"][ib], ours["i2"][ia] - theirs["i2"][ib])
        end = min(result.time[-1], reference.time[-1]) + 1e-12
        e_ref = _energy({c: x[reference.time <= end] for c, x in theirs.items()}, reference.time[reference.time <= end])
        if e_ref != 0.0:
            e = _energy({c: x[result.time <= end] for c, x in ours.items()}, result.time[result.time <= end])
            row["energy_err"] = (e - e_ref) / abs(e_ref)
    encoders = [f"{plant}.q1_enc", f"{plant}.q2_enc"] if plant else []
    if encoders and all(s in result.signals and s in reference.signals for s in encoders):
        row["enc_diff"], row["enc_first_s"] = encoder_differences(result, reference)
    return row


def pareto(rows: list, wall_tolerance: float = None) -> list:
    """Indices of the rows on the front of (``wall_s``, ``rms_err_m``), fastest first.

    Only ``accuracy`` rows that completed take part. Row j dominates row i when it is faster
    and not less accurate, or when it is strictly more accurate and at most ``wall_tolerance``
    (default :data:`WALL_TOLERANCE`) slower: wall times that close are within the timing noise
    of a shared machine, so the more accurate setting counts as just as fast.
    """
    tol = WALL_TOLERANCE if wall_tolerance is None else wall_tolerance
    candidates = [i for i, r in enumerate(rows) if r["kind"] == "accuracy" and not r.get("error")
                  and math.isfinite(r["wall_s"]) and math.isfinite(r["rms_err_m"])]

    def dominates(j, i):
        wj, ej, wi, ei = rows[j]["wall_s"], rows[j]["rms_err_m"], rows[i]["wall_s"], rows[i]["rms_err_m"]
        return (wj < wi and ej <= ei) or (wj <= wi * (1.0 + tol) and ej < ei)

    front = [i for i in candidates if not any(dominates(j, i) for j in candidates if j != i)]
    return sorted(front, key=lambda i: rows[i]["wall_s"])


def _run_setting(setting, scene):
    cpu, wall = time.process_time(), time.perf_counter()
    try:
        result = simulate(scene.system, mode=setting.mode, coupling=setting.coupling)
    except Exception as exc:  # noqa: BLE001 - one setting that cannot run (e.g. an FMU that does not
        # build) must not end the sweep: its row carries the message
        return None, f"{type(exc).__name__}: {exc}"
    result.extra["call_s"] = time.perf_counter() - wall
    result.extra["cpu_s"] = time.process_time() - cpu
    return result, None


def _sweep(base: Scene, chosen: list, reference, rounds: int, say) -> tuple[list, list]:
    """Run every applicable setting ``rounds`` times (interleaved); rows in ``chosen``'s order."""
    built, skipped = [], []
    for s in chosen:
        scene = s.build(base)
        if scene is None:
            skipped.append(s.name)
            continue
        plant = _plant(scene)
        scene = replace(scene, system=_with_record(scene.system, plant, scene.columns))
        built.append((s, scene, plant))
    for s, scene, plant in built:     # load compiled kernels and tables before anything is timed
        _run_setting(s, replace(scene, system=replace(scene.system, stop_time=min(scene.system.stop_time,
                                                                                  WARM_UP_S))))
    kept, timings = {}, {s.name: [] for s, *_ in built}
    for k in range(rounds):
        for s, scene, plant in built:
            if k > 0 and (kept[s.name][0] is None or min(timings[s.name])[0] > REPEAT_BELOW_S):
                continue
            result, failure = _run_setting(s, scene)
            if result is not None:
                timings[s.name].append((result.extra["call_s"], result.extra["cpu_s"]))
                first = kept.get(s.name, (None,))[0]
                if first is not None and plant is not None and not np.array_equal(first[f"{plant}.x"], result[f"{plant}.x"]):
                    raise RuntimeError(f"{s.name}: two runs of the same setting differ")
            if s.name not in kept or kept[s.name][0] is None:
                kept[s.name] = (result, failure)
            if k == 0:
                wall = result.extra["call_s"] if result is not None else float("nan")
                say(f"  {s.name:<36s} {wall:7.2f} s" + (f"  {failure}" if failure else ""))
    rows = []
    for s, scene, plant in built:
        result, failure = kept[s.name]
        row = {"setting": s.name, "kind": s.kind, "what": s.what, "wall_s": float("nan"), "cpu_s": float("nan"),
               "error": failure or ""}
        if result is not None:
            row["wall_s"] = min(w for w, _ in timings[s.name])
            row["cpu_s"] = min(c for _, c in timings[s.name])
            row.update(measure(result, reference, scene))
            columns = {"t": result.time}
            columns.update({name: result[sig] for name, sig in scene.columns.items()})
            row["e_ef_mm"] = scene_metrics(scene, columns, row["wall_s"], result.completed)["e_ef_mm"]
            if result.error:
                row["error"] = str(result.error)
        rows.append(row)
    return rows, skipped


def _relative(rows: list) -> None:
    base = next((r for r in rows if r["setting"] == "defaults"), None)
    front = set(pareto(rows))
    for i, r in enumerate(rows):
        r["pareto"] = i in front
        r.setdefault("e_ef_mm", float("nan"))
        for key in ("rms_err_m", "max_err_m", "residual_m", "current_err_A", "energy_err"):
            r.setdefault(key, float("nan"))
        r.setdefault("enc_diff", "")
        r.setdefault("enc_first_s", float("nan"))
        ok = base is not None and not r["error"]
        r["speedup"] = base["wall_s"] / r["wall_s"] if ok and r["wall_s"] > 0 else float("nan")
        r["gain"] = (base["rms_err_m"] / r["rms_err_m"] if ok and r["rms_err_m"] > 0 else float("nan"))


def _noquant(base: Scene, rounds: int, say) -> list:
    """The coupling settings against a reference without encoder quantisation (the full sweep)."""
    plant = _plant(base)
    if plant is None or not _drives(base):
        return []
    smooth = _change(base, [plant], encoder_counts=FINE_ENCODER)
    say(f"no-quantisation study: reference of {base.name} with {FINE_ENCODER} encoder counts ...")
    reference = reference_run(smooth)
    chosen = [Setting("defaults", "accuracy", "encoder 2^30 counts", _unchanged)]
    chosen += [Setting(f"group {n}", "accuracy", f"drives + plant at 1/{n} ms", _group(n)) for n in (4, 16, 32, 64)]
    chosen += [Setting(f"drives in plant, substeps={n}", "accuracy", f"drives in the plant, RK4 {n} steps per 1 ms",
                       _in_plant(substeps=n)) for n in (2, 4, 8)]
    rows, _ = _sweep(smooth, chosen, reference, rounds, say)
    _relative(rows)
    for r in rows:
        r["enc_diff"], r["enc_first_s"] = "", float("nan")   # at 2^30 counts not a diagnostic
    return rows
