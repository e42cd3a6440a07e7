"""FMUs that parcosim did not build: components given as an FMU file, and how to tell.

A :class:`fmus.system.Component` whose ``model`` is a path ending in ``.fmu`` names any
FMI 2.0 co-simulation FMU (a supplier's drive, a Modelica export): the master runs it
through fmpy in either mode, beside our components (:mod:`fmus.master`).  The FMUs that
``parcosim build`` makes carry a mark (:data:`MARK`), so the build never overwrites a
file it did not make and ``--mode fmu`` never loads a foreign file in place of ours.
"""
from __future__ import annotations

import json
import zipfile
from dataclasses import replace
from pathlib import Path

#: The file in an FMU's archive that says parcosim built it, and which model it is.
MARK = "resources/parcosim_build.json"


def is_fmu_file(model) -> bool:
    """True when a component's ``model`` names an FMU file rather than a parcosim model."""
    return str(model).lower().endswith(".fmu")


def built_by_parcosim(path, model: str) -> bool:
    """True when ``path`` is an FMU that ``parcosim build`` made for ``model``."""
    try:
        with zipfile.ZipFile(path) as z:
            return json.loads(z.read(MARK)).get("model") == model
    except (KeyError, OSError, ValueError, zipfile.BadZipFile):
        return False


def mark_file(directory: Path, model: str) -> Path:
    """Write the mark for ``model`` into ``directory`` (bundled as a resource by the build)."""
    path = Path(directory) / Path(MARK).name
    path.write_text(json.dumps({"model": model, "built_by": "parcosim"}) + "\n")
    return path


def replace_components(system, replacements: dict):
    """``system`` with components swapped for FMU files.

    Parameters
    ----------
    system : fmus.system.System
    replacements : dict
        Instance name -> path of an FMI 2.0 co-simulation ``.fmu`` file.  The component
        keeps its name, parameters, connections and sub-steps; parameters the FMU does not
        have are skipped when it runs, with one warning (:func:`fmus.master.simulate`).

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


def model_identifier(path) -> str:
    """The co-simulation model identifier of the FMU at ``path``."""
    from fmpy import read_model_description

    return read_model_description(str(path), validate=False).coSimulation.modelIdentifier
