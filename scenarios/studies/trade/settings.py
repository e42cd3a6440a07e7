"""The trade study's settings: each is the scene with one change (:class:`Setting`), of kind
"accuracy" (the same model computed differently) or "fidelity" (a different model); :func:`settings`
lists the sweep's (package doc, :mod:`scenarios.studies.trade`)."""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

from scenarios.scenes.scene import Scene
from scenarios.scenes.thesis import Fidelity, bench
from scenarios.scenes.transforms import drives_in_plant, with_sample_time

#: Coarser sample times of the sweep (fidelity rows) [s].
SAMPLE_TIMES = (2e-3, 4e-3)


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


def _change(scene: Scene, names, component_substeps: int | None = None, **parameters) -> Scene:
    """``scene`` with the components ``names`` given ``parameters`` (a plant's ``substeps``: its
    RK4 steps) and the master's ``Component.substeps`` (``component_substeps``)."""
    components = []
    for c in scene.system.components:
        if c.name in names:
            c = replace(c, parameters={**c.parameters, **parameters},
                        substeps=c.substeps if component_substeps is None else component_substeps)
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
        return None if plant is None else _change(scene, [plant], component_substeps=n)
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
        scene = _change(scene, drives, component_substeps=n, **drive_parameters)
        return _change(scene, [plant], component_substeps=n)
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
        Setting("no viscous friction", "fidelity", "viscous=False (b = 0; the current controller stays "
                "designed for the motor's b)", _fidelity(viscous=False)),
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
