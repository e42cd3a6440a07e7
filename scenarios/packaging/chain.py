"""A scene as a package for Jacobi masters: its control chain and its plant, two FMU instances.

Ecos, libcosim and fmpy's SSP runner step every instance from the values all held at the
step's start, so every connection of a scene adds a step of delay: exported component by
component, the bench's loop trajectory -> derivator -> controller -> drive -> plant runs
about 90 times worse there than in our master (docs/ssp.md).  :func:`package_scene` cuts
the scene in two instead:

* ``plant``: the mechanism's FMU, the scene's own plant component: on the bench the
  ``FiveBarPlant`` with its torques ``tau1``, ``tau2`` from the drives; in
  ``thesis_sim_circle`` from the controller; after
  :func:`scenarios.scenes.transforms.drives_in_plant` (``--drives-in-plant N``) the
  ``ActuatedFiveBarPlant`` in voltage mode, the voltages from the drives' current
  controllers.
* ``control``: the FMU ``ControlChain`` (:class:`fmus.systemfmu.cores.ChainCore`): every other
  component of the scene (trajectory, derivator, controller, observers, drives: foreign
  ones too, run there through fmpy from its resources) stepped in our master's order, one
  sample ahead, with the plant predicted by the scene's plant component as the model.

A foreign plant cannot be packaged (the chain needs our model of it).

Connections: the plant's outputs the chain reads (on the bench the encoder angles and the
shaft speeds the drives' back-emf needs; in thesis_sim the exact angles and speeds) go to
the chain's inputs of the same names, the chain's commands (``tau1``, ``tau2`` or
``v_ref1``, ``v_ref2``) to the plant.  The scene's recorded
signals keep their names on the plant (``plant.x``) and become outputs of the chain named
by the signal (``control.traj.x_d``).
"""
from __future__ import annotations

import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fmus.systemfmu.cores import ChainCore, chain_interface
from fmus.cosim.foreign import is_fmu_file
from fmus.systemfmu.export import build_system_fmu
from fmus.ssp.export import export_ssp
from fmus.cosim.backends import InProcessInstance
from fmus.cosim.system import Component, Connection, System, split_signal

from scenarios.scenes.scene import Scene

PLANT = "plant"
CONTROL = "control"
CHAIN_MODEL = "ControlChain"


@dataclass(frozen=True)
class Package:
    """A scene cut for a Jacobi master.

    Parameters
    ----------
    scene : Scene
        The scene whose columns name the package's signals (``columns``).
    system : System
        The two instances ``control`` (model :data:`CHAIN_MODEL`) and ``plant``.
    chain : System
        What the ``control`` FMU steps inside: the scene, whose plant component is the
        chain's model of the plant.
    """

    scene: Scene
    system: System
    chain: System


def package_scene(scene: Scene) -> Package:
    """Cut ``scene`` into its control chain and its plant (module docstring).

    Raises
    ------
    ValueError
        The scene has no component ``plant`` of model ``FiveBarPlant`` or
        ``ActuatedFiveBarPlant`` (a foreign plant among them), or a multi-rate component.
    """
    models = {c.name: c.model for c in scene.system.components}
    if is_fmu_file(models.get(PLANT, "")):
        raise ValueError(f"scene {scene.name}: the plant is an FMU file ({models[PLANT]}); the package's control "
                         "chain predicts the plant with a parcosim model of it, so the plant must be ours "
                         "(export the scene --per-component, or as one FMU with export-fmu)")
    if models.get(PLANT) not in ("FiveBarPlant", "ActuatedFiveBarPlant"):
        raise ValueError(f"scene {scene.name}: the default package (control chain + plant) is made for the 5R "
                         f"plant (a FiveBarPlant named {PLANT!r}); export this scene with --per-component, "
                         "or as one FMU with export-fmu")
    chain = scene.system
    if any(c.substeps != 1 for c in chain.components):
        raise ValueError(f"scene {scene.name}: multi-rate components cannot be packaged (substeps = 1 needed)")
    measured, commanded = chain_interface(chain, PLANT)
    plant = chain.component(PLANT)
    parameters = dict(plant.parameters)
    if plant.model == "ActuatedFiveBarPlant":
        parameters["mode"] = "voltage"
    connections = [Connection(f"{PLANT}.{m}", f"{CONTROL}.{m}") for m in measured]
    connections += [Connection(f"{CONTROL}.{name}", f"{PLANT}.{name}") for name in commanded]

    def moved(signal):
        return signal if split_signal(signal)[0] == PLANT else f"{CONTROL}.{signal}"

    system = System((Component(CONTROL, CHAIN_MODEL, {}), Component(PLANT, plant.model, parameters)),
                    tuple(connections), tuple(moved(s) for s in chain.record), chain.stop_time, chain.step)
    columns = {name: moved(signal) for name, signal in scene.columns.items()}
    packaged = replace(scene, system=system, columns=columns,
                       description=scene.description + "; packaged for Jacobi masters (control chain + plant)")
    return Package(packaged, system, chain)


def export_package(scene: Scene, path, fmu_dir=None) -> Path:
    """Write ``scene`` as an SSP package for Jacobi masters (:func:`package_scene`) to
    ``path`` and return its path.

    The ``ControlChain`` FMU is built for the scene (:func:`fmus.systemfmu.export.build_system_fmu`);
    the plant's FMU comes from ``fmu_dir`` (built there when missing or stale).  Every
    instance's parameters are baked into its FMU's start values (``bake`` of
    :func:`fmus.ssp.export.export_ssp`), so the package runs as it is in tools that ignore
    parameter bindings.
    """
    package = package_scene(scene)
    with tempfile.TemporaryDirectory(prefix="parcosim_chain_") as tmp:
        chain = build_system_fmu("chain", package.chain, Path(tmp) / f"{CHAIN_MODEL}.fmu", plant=PLANT)
        return export_ssp(package.system, path, fmu_dir, fmus={CHAIN_MODEL: chain})


@dataclass
class PackageRun:
    """A package run in process by :func:`run_jacobi`: the plant's end effector, the
    reference, and the chain (its ``corrections``)."""

    time: np.ndarray
    x: np.ndarray
    y: np.ndarray
    x_d: np.ndarray
    y_d: np.ndarray
    chain: ChainCore


def run_jacobi(package: Package, plant_parameters: dict | None = None, zero_first_inputs: bool = False,
               zero_start: bool = True) -> PackageRun:
    """``package`` stepped as a Jacobi master steps it, in process: both instances read what
    the other held at the step's start (what Ecos, libcosim and fmpy do with the FMUs).

    ``plant_parameters`` change the real plant only (the chain keeps its model);
    ``zero_first_inputs`` feeds the plant zeros on the first step, as fmpy's SSP runner
    does; ``zero_start`` is the chain's (:class:`fmus.systemfmu.cores.ChainCore`).
    """
    chain = ChainCore(package.chain, PLANT, zero_start=zero_start)
    component = package.system.component(PLANT)
    plant = InProcessInstance(component.model, PLANT)
    measured = [split_signal(c.source)[1] for c in package.system.connections if c.source.startswith(f"{PLANT}.")]
    commands = [split_signal(c.target)[1] for c in package.system.connections if c.target.startswith(f"{PLANT}.")]
    plant.bind([plant.variables[n] for n in commands], [plant.variables[n] for n in measured + ["x", "y"]])
    chain.initialize()
    plant.initialize({**component.parameters, **(plant_parameters or {})}, 0.0)
    h, rows, t = package.system.step, [], 0.0

    def row():
        outputs, recorded = plant.get_outputs(), chain.recorded()
        rows.append((outputs[-2], outputs[-1], recorded["traj.x_d"], recorded["traj.y_d"]))

    row()
    for k in range(package.system.steps):
        outputs = plant.get_outputs()
        command = chain.command()
        plant.set_inputs([0.0 if (zero_first_inputs and k == 0) else command[n] for n in commands])
        plant.do_step(t, h)
        chain.step(t, h, dict(zip(measured, outputs[:len(measured)])))
        t += h
        row()
    plant.close()
    x, y, x_d, y_d = np.array(rows).T
    return PackageRun(np.arange(len(x)) * h, x, y, x_d, y_d, chain)
