"""FMUs made for one system: a scene's whole loop (``ClosedLoop``), a package's chain
(``ControlChain``), and copies of an FMU with other start values.

* :func:`export_fmu` (``parcosim export-fmu SCENE OUT.fmu``): the whole closed loop as one
  FMI 2.0 co-simulation FMU (:mod:`fmus.slaves.parcosim_closedloop`).
* :func:`build_system_fmu`: the FMU of a system slave (``ClosedLoop`` or ``ControlChain``)
  with the system in its resources (``system.json``), bundling the model packages and the
  ``fmus`` modules that step a system in process.
* :func:`with_start_values`: a copy of an FMU whose parameters start at given values, in
  its model description and, for the slave, in ``resources/start_values.json``
  (:mod:`fmus.slave.base`), with the designs those values need (``resources/designs.npz``,
  :mod:`fmus.slave.designs`): what an SSP package gives each instance so that its parameters
  hold in a tool that ignores parameter bindings (fmpy's SSP runner).
"""
from __future__ import annotations

import json
import shutil
import tempfile
import zipfile
from dataclasses import replace
from pathlib import Path
from xml.etree import ElementTree as ET

from fmus.export.archive import rewrite
from fmus.export.build import ROOT, STATE_OPTIONS, build_bundled_fmu, precompute
from fmus.export.bundle import bundle_name
from fmus.slave.designs import DESIGNS_FILE
from fmus.systemfmu.cores import FOREIGN_DIR, SYSTEM_FILE, system_to_dict
from fmus.cosim.foreign import is_fmu_file
from fmus.slave.base import START_VALUES_FILE
from fmus.slave.identity import IDENTITY_FILE
from fmus.cosim.system import System

#: Slave module and class of each system role.
ROLES = {"loop": ("parcosim_closedloop", "ClosedLoop"), "chain": ("parcosim_controlchain", "ControlChain")}


def build_system_fmu(role: str, system: System, path, plant: str = "plant") -> Path:
    """Build the FMU of ``role`` ("loop": ``ClosedLoop``; "chain": ``ControlChain``) for
    ``system`` at ``path`` (a ``.fmu`` file) and return its path.

    Raises ValueError for an unknown role, a path not ending in ``.fmu``, or a system whose
    components are not all parcosim models (their slaves run inside the FMU).
    """
    from fmus.slave.registry import SLAVES

    if role not in ROLES:
        raise ValueError(f"role = {role!r}; valid: {', '.join(ROLES)}")
    path = Path(path)
    if path.suffix.lower() != ".fmu":
        raise ValueError(f"{path}: an FMU file must end in '.fmu'")
    unknown = [f"{c.name} ({c.model})" for c in system.components if c.model not in SLAVES and not is_fmu_file(c.model)]
    if unknown:
        raise ValueError(f"cannot put {', '.join(unknown)} inside one FMU: a component is a parcosim model "
                         f"({', '.join(SLAVES)}) or an FMU file")
    module, model = ROLES[role]
    with tempfile.TemporaryDirectory(prefix="parcosim_system_") as tmp:
        tmp = Path(tmp)
        system, foreign = _carry_foreign(system, tmp)
        spec = tmp / SYSTEM_FILE
        spec.write_text(json.dumps({"role": role, "plant": plant, "system": system_to_dict(system)}, indent=1))
        # The loop takes any whole number of its steps per doStep; the chain exactly one.
        variable = "true" if role == "loop" else "false"
        return build_bundled_fmu(ROOT / "fmus" / "slaves" / f"{module}.py", model, path, resources=foreign + [spec],
                                 canHandleVariableCommunicationStepSize=variable, **STATE_OPTIONS)


def _carry_foreign(system: System, tmp: Path):
    """``system`` with each FMU-file component's file copied to ``tmp/foreign/<instance>.fmu``
    and named so (resolved in the FMU's resources, :func:`fmus.systemfmu.cores.read_system`);
    and the project files to bundle."""
    foreign = [c for c in system.components if is_fmu_file(c.model)]
    if not foreign:
        return system, []
    folder = tmp / FOREIGN_DIR
    folder.mkdir()
    components = []
    for c in system.components:
        if is_fmu_file(c.model):
            if not Path(c.model).is_file():
                raise ValueError(f"component {c.name}: no FMU file {c.model}")
            shutil.copy2(c.model, folder / f"{c.name}.fmu")
            c = replace(c, model=f"{FOREIGN_DIR}/{c.name}.fmu")
        components.append(c)
    return replace(system, components=tuple(components)), [folder]


def export_fmu(system: System, path) -> Path:
    """``system``'s whole closed loop as one FMU (``ClosedLoop``) at ``path``.

    Its run in any FMI 2.0 importer stepping it at the system's communication step is the
    master's run of ``system`` (:func:`fmus.cosim.master.simulate`, in process): outputs ``x``,
    ``y`` and the recorded signals; parameters ``<instance>.<name>`` of every component.
    The system's plant must be the instance ``plant`` (its ``x``, ``y`` are the outputs).
    """
    return build_system_fmu("loop", closed_loop_system(system), path)


def closed_loop_system(system: System) -> System:
    """``system`` as its ClosedLoop FMU steps it: ``plant.x``, ``plant.y`` recorded first.
    Raises ValueError when it has no component ``plant``."""
    names = [c.name for c in system.components]
    if "plant" not in names:
        raise ValueError(f"the system needs a component 'plant' (its x, y are the FMU's outputs); it has {names}")
    record = tuple(dict.fromkeys(("plant.x", "plant.y") + tuple(system.record)))
    return System(system.components, system.connections, record, system.stop_time, system.step)


def _start_text(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def with_start_values(fmu, values: dict, path) -> Path:
    """A copy of ``fmu`` at ``path`` whose variables ``values`` (name -> value of the
    variable's type) start there: the ``start`` attributes of its modelDescription.xml and,
    read by every parcosim slave at instantiation, ``resources/start_values.json``; the
    designs its initialisation computes with them are computed here (``resources/designs.npz``,
    beside the FMU's own: :func:`_designs_with`)."""
    fmu, path = Path(fmu), Path(path)
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    declared = set()
    for sv in root.find("ModelVariables").findall("ScalarVariable"):
        name = sv.get("name")
        declared.add(name)
        if name in values:
            typed = next(iter(sv))
            typed.set("start", _start_text(values[name]))
    missing = set(values) - declared
    if missing:
        raise ValueError(f"{fmu.name} has no variables {sorted(missing)}")
    ET.indent(root)
    xml = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    members = {"modelDescription.xml": xml, f"resources/{START_VALUES_FILE}": json.dumps(values, indent=1)}
    computed = _designs_with(fmu, values)
    if computed is not None:
        members[f"resources/{DESIGNS_FILE}"] = computed
    return rewrite(fmu, path, members)


def _designs_with(fmu: Path, values: dict) -> bytes | None:
    """The designs file (:mod:`fmus.slave.designs`) of ``fmu`` started at ``values``, computed
    here; None (the FMU keeps its own) when it carries none (its initialisation computes
    none, or it is not one of our slaves) or was built from other sources than these (their
    code makes its designs)."""
    with zipfile.ZipFile(fmu) as z:
        names = set(z.namelist())
        if f"resources/{DESIGNS_FILE}" not in names or "resources/slavemodule.txt" not in names:
            return None         # its initialisation computes none, or it is not ours
        identity = json.loads(z.read(f"resources/{IDENTITY_FILE}"))
        module = z.read("resources/slavemodule.txt").decode().strip().rsplit(".", 1)[-1]
        if identity.get("package") != bundle_name():
            return None
        with tempfile.TemporaryDirectory(prefix="parcosim_designs_") as tmp:
            folder = Path(tmp) / "resources"
            bundled = (f"resources/{identity['package']}", "resources/pythonfmu/")
            z.extractall(tmp, [n for n in names if n.startswith("resources/") and not n.startswith(bundled)])
            folder.mkdir(exist_ok=True)
            (folder / START_VALUES_FILE).write_text(json.dumps(values))
            computed = precompute(module, identity["model"], folder, Path(tmp) / DESIGNS_FILE)
            return computed.read_bytes() if computed else None
