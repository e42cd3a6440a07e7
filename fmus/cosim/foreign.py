"""FMUs that parcosim did not build: components given as an FMU file, and how to tell.

A :class:`fmus.cosim.system.Component` whose ``model`` is a path ending in ``.fmu`` names any
FMI 2.0 co-simulation FMU (a supplier's drive, a Modelica export): the master runs it
through fmpy in either mode, beside our components (:mod:`fmus.cosim.master`).  The FMUs that
``parcosim build`` makes carry a mark (:mod:`fmus.export.mark`), so the build never overwrites a
file it did not make and ``--mode fmu`` never loads a foreign file in place of ours.
"""
from __future__ import annotations

import warnings
from dataclasses import replace
from pathlib import Path


def is_fmu_file(model) -> bool:
    """True when a component's ``model`` names an FMU file rather than a parcosim model."""
    return str(model).lower().endswith(".fmu")


def replace_components(system, replacements: dict):
    """``system`` with components swapped for FMU files.

    Parameters
    ----------
    system : fmus.cosim.system.System
    replacements : dict
        Instance name -> path of an FMI 2.0 co-simulation ``.fmu`` file.  The component
        keeps its name, parameters, connections and sub-steps; parameters the FMU does not
        have are skipped when it runs, with one warning (:func:`fmus.cosim.master.simulate`).

    Raises
    ------
    ValueError
        An instance the system does not have (the message lists its instances), or a path
        that is not an existing ``.fmu`` file.
    """
    names = [c.name for c in system.components]
    for name, path in replacements.items():
        if name not in names:
            raise ValueError(f"--replace {name}=...: no instance {name!r}; instances: {', '.join(names)}")
        if not is_fmu_file(path) or not Path(path).is_file():
            raise ValueError(f"--replace {name}={path}: not an existing .fmu file")
    components = tuple(replace(c, model=str(Path(replacements[c.name]).resolve())) if c.name in replacements else c
                       for c in system.components)
    return replace(system, components=components)


def without_missing_parameters(system, variables: dict) -> tuple:
    """``system`` without the parameters that its FMU-file components do not have (a scene
    written for our drive sets ``method``, ``J_design`` ...), and one line that lists them
    ("" when none is missing).

    ``variables``: instance name -> the names of its FMU's variables.
    """
    skipped, components = [], []
    for c in system.components:
        missing = [n for n in c.parameters if n not in variables[c.name]] if is_fmu_file(c.model) else []
        if missing:
            skipped.append(f"{c.name} ({Path(c.model).name}): {', '.join(missing)}")
            c = replace(c, parameters={n: v for n, v in c.parameters.items() if n not in missing})
        components.append(c)
    if not skipped:
        return system, ""
    return (replace(system, components=tuple(components)),
            "parameters the foreign FMUs do not have are skipped: " + "; ".join(skipped))


def named_models(system):
    """``system`` with each FMU-file component's model replaced by its FMU's model
    identifier, and identifier -> file: the ``system`` and ``fmus`` arguments of
    :func:`fmus.ssp.export.export_ssp`, which carries the files into the package.

    Parameters the FMU does not have are left out, with one warning that lists them.

    Raises
    ------
    ValueError
        Two different files with one model identifier.
    """
    from fmpy import read_model_description

    descriptions = {c.model: read_model_description(c.model, validate=False)
                    for c in system.components if is_fmu_file(c.model)}
    system, skipped = without_missing_parameters(system, {
        c.name: {v.name for v in descriptions[c.model].modelVariables} if c.model in descriptions else set()
        for c in system.components})
    if skipped:
        warnings.warn(skipped, stacklevel=2)
    fmus, components = {}, []
    for c in system.components:
        if is_fmu_file(c.model):
            identifier = descriptions[c.model].coSimulation.modelIdentifier
            if fmus.setdefault(identifier, c.model) != c.model:
                raise ValueError(f"component {c.name}: {c.model} and {fmus[identifier]} are both model "
                                 f"{identifier!r}; an SSP package names each model's FMU once")
            c = replace(c, model=identifier)
        components.append(c)
    return replace(system, components=tuple(components)), fmus


def foreign_components(system) -> list:
    """``"instance (path)"`` for each component of ``system`` given as an FMU file."""
    return [f"{c.name} ({c.model})" for c in system.components if is_fmu_file(c.model)]
