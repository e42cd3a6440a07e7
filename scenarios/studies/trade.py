"""Speed against accuracy: a sweep over a scene's settings, measured against its monolithic reference.

``parcosim trade [SCENE] [--quick] [--out DIR]`` is :func:`run_trade`::

    from scenarios.studies.trade import run_trade
    trade = run_trade("bench_circle_TCMDx", quick=True, out_dir="out/trade")
    for row in trade.rows:
        print(row["setting"], row["wall_s"], row["rms_err_m"])

Each setting is the scene with one change (:data:`Setting.build` rewrites its
:class:`fmus.cosim.system.System`). Every run is compared with ONE reference run of the unmodified
scene (:func:`scenarios.reference.reference_run`, the truth). The deviation means different
things for the two kinds of row:

* ``kind = "accuracy"``: the same model computed differently (plant integrator, sub-steps
  and tolerances, the drive's electrical integration, drive/plant sub-stepping, the drive's
  torque output, the drives integrated inside the plant, Gauss-Seidel or Jacobi, ``fmu`` or
  ``inprocess``). The deviation is an error. The Pareto front (wall time against RMS error)
  is taken over these rows only.
* ``kind = "fidelity"``: a different model (the :class:`scenarios.scenes.thesis.Fidelity` switches,
  the controller's exact or tabulated model and its grid, another sample time). The
  deviation is what the effect changes in the result, not an error. These rows are in the
  table and the plot (another marker), never on the front.

Columns of ``trade.csv`` (one row per setting): ``setting``, ``kind``, ``what`` (the change);
``wall_s`` (the whole :func:`fmus.cosim.master.simulate` call: loading, initialisation and stepping,
best of the rounds, so one-time costs such as imports and table builds drop out);
``cpu_s`` (the process's CPU time over the same call); ``speedup`` (the defaults' wall over
this one); ``rms_err_m`` and ``max_err_m`` (end-effector distance from the reference over the
whole run); ``gain`` (the defaults' RMS over this one); ``residual_m`` (largest loop-closure
residual, 5.18); ``current_err_A`` (RMS over the samples of the drives' current deviation,
sqrt(Δi1² + Δi2²)); ``energy_err`` (relative deviation of the electrical energy the drives
draw, ∫ (v1 i1 + v2 i2) dt); ``enc_diff`` (samples at which an encoder reading differs from the
reference's) and ``enc_first_s`` (the first one's time); ``e_ef_mm`` (the thesis' tracking
error, 7.31); ``pareto``; ``error`` (why a run stopped). Columns that do not apply are empty.

The full sweep also writes ``noquant.csv``: the drive/plant coupling settings against a
reference of the same scene with the encoders' quantisation removed (2^30 counts per
revolution, in the reference and in every run): what those settings buy where a change
smaller than one encoder count does not flip the closed loop onto another path (see
``docs/trade.md``).
"""
from __future__ import annotations

import csv
import math
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from fmus.cosim.master import simulate
from fmus.cosim.system import System

from scenarios.run.metrics import rms_norm, scene_metrics
from scenarios.reference import common_rows, deviation, encoder_differences, reference_run
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.scene import Scene
from scenarios.scenes.thesis import Fidelity, bench
from scenarios.scenes.transforms import drives_in_plant, with_sample_time

DEFAULT_SCENE = "bench_circle_TCMDx"
#: Simulated time of the quick sweep [s].
QUICK_STOP_TIME = 1.0
#: Timing rounds (each round runs every setting once, interleaved; the best round counts).
FULL_ROUNDS = 5
QUICK_ROUNDS = 1
#: Settings whose first run takes longer than this are not repeated [s].
REPEAT_BELOW_S = 5.0
COLUMNS = ("setting", "kind", "what", "wall_s", "cpu_s", "speedup", "rms_err_m", "max_err_m", "gain", "residual_m",
           "current_err_A", "energy_err", "enc_diff", "enc_first_s", "e_ef_mm", "pareto", "error")
#: Coarser sample times of the sweep (fidelity rows) [s].
SAMPLE_TIMES = (2e-3, 4e-3)
#: Each setting runs this long once before it is timed [s].
WARM_UP_S = 0.02
#: Wall times within this fraction of each other count as equally fast on the front.
WALL_TOLERANCE = 0.10
#: Encoder counts that make the quantisation negligible (the no-quantisation study).
FINE_ENCODER = 2 ** 30


@dataclass(frozen=True)
class Setting:
    """One point of the sweep.

    ``build(scene)`` returns the scene to run, or None when the setting does not apply to it
    (e.g. a drive setting on a scene without drives).
    """

    name: str
    kind: str                      # "accuracy" or "fidelity"
    what: str
    build: Callable
    mode: str = "inprocess"
    coupling: str = "gauss-seidel"


@dataclass
class Trade:
    """What :func:`run_trade` measured and wrote."""

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


# --- settings ---------------------------------------------------------------------------

def _has(scene: Scene, *names) -> bool:
    present = {c.name for c in scene.system.components}
    return all(n in present for n in names)


def _drives(scene: Scene) -> list:
    return [c.name for c in scene.system.components if c.model == "DCMotorDrive"]


#: Models that are the scene's plant (its end effector is the measured output).
PLANT_MODELS = ("FiveBarPlant", "ActuatedFiveBarPlant")


def _plant(scene: Scene) -> str | None:
    plants = [c.name for c in scene.system.components if c.model in PLANT_MODELS]
    return plants[0] if len(plants) == 1 else None


def _change(scene: Scene, names, substeps: int | None = None, **parameters) -> Scene:
    """``scene`` with the components ``names`` given ``parameters`` (and ``Component.substeps``)."""
    components = []
    for c in scene.system.components:
        if c.name in names:
            c = replace(c, parameters={**c.parameters, **parameters},
                        substeps=c.substeps if substeps is None else substeps)
        components.append(c)
    return replace(scene, system=replace(scene.system, components=tuple(components)))


def _plant_setting(**parameters):
    def build(scene):
        plant = _plant(scene)
        return None if plant is None else _change(scene, [plant], **parameters)
    return build


def _plant_multirate(n: int):
    def build(scene):
        plant = _plant(scene)
        return None if plant is None else _change(scene, [plant], substeps=n)
    return build


def _drive_setting(**parameters):
    def build(scene):
        drives = _drives(scene)
        return _change(scene, drives, **parameters) if drives else None
    return build


def _group(n: int, **drive_parameters):
    """Drives and plant stepped together at h/n (one master group), drive parameters changed."""
    def build(scene):
        drives, plant = _drives(scene), _plant(scene)
        if not drives or plant is None:
            return None
        scene = _change(scene, drives, substeps=n, **drive_parameters)
        return _change(scene, [plant], substeps=n)
    return build


def _in_plant(**plant_parameters):
    """The drives moved into the plant (one ODE, :func:`scenarios.scenes.transforms.drives_in_plant`)."""
    def build(scene):
        if not _drives(scene) or _plant(scene) is None:
            return None
        return drives_in_plant(scene, **plant_parameters)
    return build


def _controller_setting(**parameters):
    def build(scene):
        ctrl = [c.name for c in scene.system.components if c.model == "PositionController"]
        return _change(scene, ctrl, **parameters) if ctrl else None
    return build


def _bench_origin(scene: Scene):
    """(strategy, kind, model) of a bench scene, or None for any other scene (the twin's
    ``bench_real_*`` too: rebuilding it from switches would drop its calibrated effects)."""
    if not scene.name.startswith("bench_") or scene.name.startswith("bench_real_") or not _has(scene, "traj", "ctrl"):
        return None
    kind = scene.system.component("traj").parameters.get("kind")
    model = scene.system.component("ctrl").parameters.get("model", "tabulated")
    return scene.strategy, kind, model


def _fidelity(**switches):
    """The bench scene rebuilt with :class:`Fidelity` switches (bench scenes only)."""
    def build(scene):
        origin = _bench_origin(scene)
        if origin is None:
            return None
        strategy, kind, model = origin
        rebuilt = bench(strategy, kind, model, fidelity=Fidelity(**switches))
        return replace(rebuilt, system=replace(rebuilt.system, stop_time=scene.system.stop_time))
    return build


def _sampled_at(T: float, build=None):
    """The scene (after ``build``, if given) at sample time ``T``."""
    def rebuild(scene):
        scene = scene if build is None else build(scene)
        return None if scene is None else with_sample_time(scene, T)
    return rebuild


def _unchanged(scene):
    return scene


def settings(quick: bool = False) -> list:
    """The sweep: :class:`Setting` list, ``defaults`` first."""
    acc = [Setting("defaults", "accuracy", "the scene as it is (plant RK4 1 step, drive exact, GS, in-process)",
                   _unchanged)]
    acc.append(Setting("plant rk4 substeps=4", "accuracy", "plant RK4, 4 steps per 1 ms",
                       _plant_setting(substeps=4)))
    if not quick:
        acc += [
            Setting("plant dopri5 rtol=1e-10", "accuracy", "plant adaptive DOPRI5, rtol 1e-10, atol 1e-13",
                    _plant_setting(method="dopri5", rtol=1e-10, atol=1e-13)),
            Setting("plant dopri5 rtol=1e-6", "accuracy", "plant adaptive DOPRI5, rtol 1e-6, atol 1e-9",
                    _plant_setting(method="dopri5", rtol=1e-6, atol=1e-9)),
            Setting("plant project", "accuracy", "plant: Newton projection on the constraints after each step",
                    _plant_setting(project=True)),
            Setting("plant baumgarte=0", "accuracy", "plant: no Baumgarte stabilisation",
                    _plant_setting(baumgarte=0.0)),
            Setting("plant multirate 4", "accuracy", "plant alone stepped 4 x 0.25 ms (Component.substeps), "
                    "drive torque held over the 1 ms", _plant_multirate(4)),
        ]
    acc.append(Setting("drive euler", "accuracy", "drive current by explicit Euler (= Fidelity electrics='euler')",
                       _drive_setting(method="euler")))
    for n in ((4,) if quick else (2, 4, 8, 16, 32)):
        acc.append(Setting(f"group {n}", "accuracy", f"drives + plant stepped together at 1/{n} ms "
                           "(controller, observers, derivator at 1 ms)", _group(n)))
    acc.append(Setting("torque end", "accuracy", "the drives hand the plant their torque at the step's end "
                       "(DCMotorDrive's own default) instead of its mean over the step",
                       _drive_setting(torque_output="end")))
    for n in ((8,) if quick else (1, 2, 4, 8, 16)):
        acc.append(Setting("drives in plant" + ("" if n == 1 else f", substeps={n}"), "accuracy",
                           "drives' currents and the mechanism as one ODE in the plant (ActuatedFiveBarPlant), "
                           f"RK4 {n} step{'s' if n > 1 else ''} per 1 ms", _in_plant(substeps=n)))
    if not quick:
        acc.append(Setting("drives in plant, substeps=8, fmu", "accuracy",
                           "as 'drives in plant, substeps=8', the built FMUs through fmpy", _in_plant(substeps=8),
                           mode="fmu"))
    acc.append(Setting("jacobi", "accuracy", "Jacobi coupling: every sample read one step late", _unchanged,
                       coupling="jacobi"))
    if not quick:
        acc.append(Setting("fmu", "accuracy", "the built FMUs through fmpy (raw FMI calls)", _unchanged,
                           mode="fmu"))
    fid = [
        Setting("ideal actuators", "fidelity", "electrics='ideal': torque sources, no drives or observers",
                _fidelity(electrics="ideal")),
        Setting("no observer", "fidelity", "observer=False: current loops read the drive's own current",
                _fidelity(observer=False)),
    ]
    if quick:
        return acc + fid
    fid += [
        Setting("quasi-static electrics", "fidelity", "electrics='quasi_static': L neglected in the drive",
                _fidelity(electrics="quasi_static")),
        Setting("no Coulomb friction", "fidelity", "coulomb=False (mu = 0)", _fidelity(coulomb=False)),
        Setting("no viscous friction", "fidelity", "viscous=False (b = 0; also re-designs the current controller "
                "for b = 0)", _fidelity(viscous=False)),
        Setting("viscous b=1e-7", "fidelity", "b = 1e-7 N m s/rad in the drives: the friction nearly gone, the "
                "current controller designed for it", _drive_setting(b=1e-7)),
        Setting("exact angles", "fidelity", "encoder=False: derivator and controller read the exact angles",
                _fidelity(encoder=False)),
        Setting("no derivator", "fidelity", "derivator=False: exact speeds, zero accelerations",
                _fidelity(derivator=False)),
        Setting("point-mass links", "fidelity", "link_inertias=False", _fidelity(link_inertias=False)),
        Setting("m0 = 0.05 kg", "fidelity", "end-effector mass 0.05 kg (unknown to the controller)",
                _fidelity(m0=0.05)),
        Setting("vertical plane", "fidelity", "gravity (0, -9.81, 0) m/s² (unknown to the controller)",
                _fidelity(gravity=(0.0, -9.81, 0.0))),
        Setting("model error 20 %", "fidelity", "controller model inertias x 1.2", _fidelity(model_error=0.2)),
        Setting("controller exact model", "fidelity", "inverse dynamics every sample instead of the 5 mm table",
                _controller_setting(model="exact")),
        Setting("table 10 mm", "fidelity", "tabulated model on a 10 mm grid", _controller_setting(grid_step=0.010)),
        Setting("table 2.5 mm", "fidelity", "tabulated model on a 2.5 mm grid",
                _controller_setting(grid_step=0.0025)),
        Setting("ideal + exact sensors", "fidelity", "ideal actuators, exact angles, no derivator",
                _fidelity(electrics="ideal", encoder=False, derivator=False)),
    ]
    fid += [Setting(f"sample {1e3 * T:g} ms", "fidelity", f"communication step and every sample time T = "
                    f"{1e3 * T:g} ms (derivator filters and current controllers designed for it)", _sampled_at(T))
            for T in SAMPLE_TIMES]
    fid += [Setting(f"ideal + exact sensors, sample {1e3 * T:g} ms", "fidelity",
                    f"ideal actuators, exact angles, no derivator, at T = {1e3 * T:g} ms",
                    _sampled_at(T, _fidelity(electrics="ideal", encoder=False, derivator=False)))
            for T in SAMPLE_TIMES]
    return acc + fid


# --- measuring --------------------------------------------------------------------------

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
                row["error"] = result.error
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


# --- output -----------------------------------------------------------------------------

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


# --- the command ------------------------------------------------------------------------

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


def main(argv=None) -> int:
    """``python -m scenarios.studies.trade [SCENE] [--quick] [--out DIR]``."""
    from parcosim.cli import main as cli

    return cli(["trade", *(sys.argv[1:] if argv is None else argv)])


if __name__ == "__main__":
    raise SystemExit(main())
