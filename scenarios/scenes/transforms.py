"""A scene changed, not a new one: its drives moved into the plant, another sample time, instances
run as FMU files.  (A scene perturbed by sample: :mod:`scenarios.scenes.perturb`.)"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from fmus.cosim.foreign import replace_components
from fmus.cosim.system import Connection
from scenarios.scenes.scene import Scene


def drive_joints(system, plant: str) -> dict:
    """Drive instance -> the plant joint (1 or 2) it drives, for every ``DCMotorDrive``.

    A drive must be wired as on the bench: its ``tau`` to exactly one of ``<plant>.tau1`` /
    ``tau2``, and that joint's ``<plant>.dq1`` / ``dq2`` to its ``omega``; otherwise a
    ValueError names the drive and the wiring it needs.
    """
    sources = {c.target: c.source for c in system.connections}
    joints = {}
    for c in system.components:
        if c.model != "DCMotorDrive":
            continue
        driven = [j for j in (1, 2) if sources.get(f"{plant}.tau{j}") == f"{c.name}.tau"]
        if len(driven) != 1:
            raise ValueError(f"drive {c.name}: its tau must drive exactly one of {plant}.tau1/tau2")
        if sources.get(f"{c.name}.omega") != f"{plant}.dq{driven[0]}":
            raise ValueError(f"drive {c.name}: omega must be {plant}.dq{driven[0]} "
                             f"(got {sources.get(f'{c.name}.omega')})")
        joints[c.name] = driven[0]
    return joints


#: Drive parameters that describe the separate drive's coupling to the plant (its own
#: electrical integration and the torque it hands over): meaningless once the plant
#: integrates the currents.
_COUPLING_ONLY = ("method", "torque_output")
#: Drive parameters shared by both drives of an ``ActuatedFiveBarPlant``.
_SHARED = ("mode", "T")


def drives_in_plant(scene: Scene, **plant_parameters) -> Scene:
    """``scene`` with its plant and its drives replaced by ONE ``ActuatedFiveBarPlant``.

    The monolithic plant-motor coupling (:mod:`plant.actuated`): the drives' currents and
    the mechanism are integrated together, the current controllers still sample at the
    communication step.  Every connection and recorded signal of ``drive<j>`` moves to the
    plant's ``*<j>`` variable (``drive1.v`` -> ``plant.v1``, ``ctrl.i_ref1 -> drive1.i_ref``
    becomes ``-> plant.i_ref1``), ``drive<j>.tau -> plant.tau<j>`` and
    ``plant.dq<j> -> drive<j>.omega`` go (they are inside), the drives' parameters move to
    the plant with the suffix j.  ``plant_parameters`` (e.g. ``substeps=8``) are set on the
    new plant.

    Raises
    ------
    ValueError
        The scene has no single ``FiveBarPlant``, no drive, or a drive not wired as on the
        bench (its torque to one plant input, the same joint's speed back), drives that
        differ in ``mode`` or ``T``, or a drive started spinning or with a current.
    """
    system = scene.system
    plants = [c for c in system.components if c.model == "FiveBarPlant"]
    if len(plants) != 1:
        raise ValueError(f"scene {scene.name}: drives_in_plant needs one FiveBarPlant, found {len(plants)}")
    plant = plants[0]
    try:
        joint_of = {name: str(j) for name, j in drive_joints(system, plant.name).items()}
    except ValueError as exc:
        raise ValueError(f"scene {scene.name}: {exc}") from None
    if not joint_of:
        raise ValueError(f"scene {scene.name}: no DCMotorDrive to move into the plant")
    parameters = dict(plant.parameters)
    for name, j in joint_of.items():
        for key, value in system.component(name).parameters.items():
            if key in ("omega0", "i0") and value != 0.0:
                raise ValueError(f"scene {scene.name}: drive {name} starts with {key} = {value!r}; "
                                 f"the actuated plant starts at rest with zero current")
            if key in _SHARED:
                if parameters.setdefault(key, value) != value:
                    raise ValueError(f"scene {scene.name}: the drives differ in {key} "
                                     f"({parameters[key]!r}, {value!r}); the actuated plant has one")
            elif key not in _COUPLING_ONLY + ("omega0", "i0"):
                parameters[f"{key}{j}"] = value
    parameters.update(plant_parameters)

    def moved(signal):
        instance, variable = signal.split(".", 1)
        if instance in joint_of:
            return f"{plant.name}.{variable}{joint_of[instance]}"
        return signal

    inside = {f"{plant.name}.tau{j}" for j in joint_of.values()} | {f"{d}.omega" for d in joint_of}
    connections = tuple(Connection(moved(c.source), moved(c.target)) for c in system.connections
                        if c.target not in inside)
    components = tuple(replace(c, model="ActuatedFiveBarPlant", parameters=parameters) if c is plant else c
                       for c in system.components if c.name not in joint_of)
    record = tuple(dict.fromkeys(moved(r) for r in system.record))
    columns = {k: moved(v) for k, v in scene.columns.items()}
    return replace(scene, system=replace(system, components=components, connections=connections, record=record),
                   columns=columns, description=scene.description + "; drives integrated in the plant")


#: Models whose discrete parts are designed for a sample time: their parameter ``T``.
SAMPLE_TIME_MODELS = ("Derivator", "DCMotorDrive", "ActuatedFiveBarPlant", "PositionController", "CurrentObserver",
                      "BalanceController")


def with_sample_time(scene: Scene, T: float) -> Scene:
    """``scene`` run at the communication step and sample time ``T`` [s] (the thesis: 1 ms).

    The step and the ``T`` of every component designed for one (:data:`SAMPLE_TIME_MODELS`:
    the derivator's Bessel filters, the drives' current controllers, the position controller's
    and the observers' samples) change together; each refuses a step its T cannot honour.  A different T is a
    different discrete controller: the trade study lists it as a fidelity change
    (docs/trade.md), the extremes suite checks 0.1 ms and 10 ms (docs/extremes.md).
    """
    if not (T > 0.0):
        raise ValueError(f"sample time T = {T!r} s must be > 0")
    components = tuple(replace(c, parameters={**c.parameters, "T": T}) if c.model in SAMPLE_TIME_MODELS else c
                       for c in scene.system.components)
    return replace(scene, system=replace(scene.system, components=components, step=T),
                   description=scene.description + f"; sample time {1e3 * T:g} ms")


def with_fmu_files(scene: Scene, replacements: dict) -> Scene:
    """``scene`` with instances run as FMU files (``parcosim run SCENE --replace I=F.fmu``):
    instance name -> path of an FMI 2.0 co-simulation FMU (:func:`fmus.cosim.foreign.replace_components`)."""
    if not replacements:
        return scene
    names = ", ".join(f"{name}={Path(path).name}" for name, path in replacements.items())
    return replace(scene, system=replace_components(scene.system, replacements),
                   description=f"{scene.description}; FMU files: {names}")
