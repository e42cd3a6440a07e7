"""``parcosim export-fmu``: a scene's whole closed loop as one FMU (fmus.systemfmu.export.export_fmu).

Its run in an importer is the master's run: fmpy.simulate_fmu as a user calls it, Ecos and
libcosim (the FMU alone in an SSP package) give ``parcosim run``'s path to the last bit;
its inner parameters act as they do in a scene; bad step sizes are refused, not stepped.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from fmus.systemfmu.export import export_fmu
from fmus.cosim.master import simulate
from fmus.ssp.export import export_ssp
from fmus.ssp.run import ecos_available
from fmus.status import RunStatus, RunError
from fmus.cosim.system import Component, System
from scenarios.scenes.catalogue import get_scene

pytestmark = [pytest.mark.fmu]

STOP = {"thesis_sim_circle": 2.0, "bench_circle_TCMDx": 1.0}
TOL = 1e-9   # m: what the issue allows; the runs are bit-identical


def _system(name, **changes):
    system = dataclasses.replace(get_scene(name).system, stop_time=STOP[name])
    if not changes:
        return system
    components = tuple(dataclasses.replace(c, parameters={**c.parameters, **{k.split(".", 1)[1]: v for k, v in
                                                                          changes.items() if k.startswith(c.name + ".")}})
                       for c in system.components)
    return dataclasses.replace(system, components=components)


@pytest.fixture(scope="module", params=tuple(STOP))
def exported(request, tmp_path_factory):
    system = _system(request.param)
    return request.param, system, export_fmu(system, tmp_path_factory.mktemp("fmu") / f"{request.param}.fmu")


def _deviation(time, x, y, reference, h):
    k = np.round(np.asarray(time) / h).astype(int)
    assert np.allclose(time, k * h, atol=1e-9)
    assert k[-1] == len(reference.time) - 1, "the run did not reach the stop time"
    return max(np.max(np.abs(x - reference["plant.x"][k])), np.max(np.abs(y - reference["plant.y"][k])))


def test_the_fmu_validates(exported):
    """Catches a system FMU that fmpy's validation rejects."""
    _, _, path = exported
    assert validate_fmu(str(path)) == []


def test_fmpy_simulate_fmu_is_parcosim_run(exported):
    """As a user calls it: stop time and step size only (fmpy then steps 16 ms at a time
    over long runs; the FMU takes 16 of its steps each time)."""
    _, system, path = exported
    reference = simulate(system)
    run = simulate_fmu(str(path), stop_time=system.stop_time, step_size=system.step, output=["x", "y"])
    assert _deviation(run["time"], run["x"], run["y"], reference, system.step) <= TOL


#: An inner parameter change per scene: the controller's lambda; the plant's start and the strategy.
CHANGES = {"thesis_sim_circle": {"ctrl.lam": 20.0}, "bench_circle_TCMDx": {"plant.x0": 0.0, "ctrl.strategy": "PDq"}}


def test_an_inner_parameter_changes_the_path_as_in_the_scene(exported):
    """Catches an exported system FMU whose inner parameters, set as its start values, are ignored or set
    on another component."""
    name, system, path = exported
    change = CHANGES[name]
    changed = simulate(_system(name, **change))
    run = simulate_fmu(str(path), stop_time=system.stop_time, step_size=system.step, output=["x", "y"],
                       start_values=change, output_interval=system.step)
    assert _deviation(run["time"], run["x"], run["y"], changed, system.step) <= TOL
    assert _deviation(run["time"], run["x"], run["y"], simulate(system), system.step) > 1e-6


def _unavailable(tool):
    if tool == "ecos":
        return ecos_available()
    from fmus.ssp.libcosim import libcosim_available

    return libcosim_available()


@pytest.mark.parametrize("tool", ["ecos", "libcosim"])
def test_the_tools_run_the_fmu_as_parcosim_run(exported, tmp_path, tool):
    """The FMU alone in a package, run by Ecos and by libcosim as by fmpy."""
    reason = _unavailable(tool)
    if reason:
        pytest.skip(f"{tool} cannot be loaded: {reason}")
    from scenarios.studies.tools import run_tool

    _, system, path = exported
    alone = System((Component("loop", "ClosedLoop"),), (), ("loop.x", "loop.y"), system.stop_time, system.step)
    package = export_ssp(alone, tmp_path / "loop.ssp", fmus={"ClosedLoop": path})
    run = run_tool(tool, package, ["loop.x", "loop.y"], system.stop_time, system.step)
    assert run.error is None
    assert _deviation(run.time, run["loop.x"], run["loop.y"], simulate(system), system.step) <= TOL


def test_a_step_that_is_not_a_whole_number_of_its_steps_is_refused(exported):
    """Catches a system FMU that steps a fraction of its communication step (its inner clock then drifts),
    or refuses it without its record."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    _, system, path = exported
    md = read_model_description(str(path))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="loop")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 2 * system.step)
    with pytest.raises(Exception, match="2"):          # fmi2Discard
        fmu.doStep(2 * system.step, 0.5 * system.step)
    variables = {v.name: v for v in md.modelVariables}
    message, record = (fmu.getString([variables[name].valueReference])[0].decode() for name in ("error", "refusal"))
    assert "step size 0.0005 s" in message and "whole multiple of h = 0.001 s" in message
    record = RunError.from_json(record)      # the system FMU's own refusal, as a record
    assert (record.kind, record.instance, record.time, record.message) == (RunStatus.REFUSED, "loop", 2 * system.step,
                                                                          message)
    fmu.terminate()
    fmu.freeInstance()


def _imports_of(source: str) -> set:
    """The ``fmus`` modules a bundled module imports, dotted below ``fmus`` (``from <bundle>.fmus.cosim.master
    import x`` -> ``cosim.master``; ``from <bundle>.fmus.slave import budget`` -> ``slave``, ``slave.budget``)."""
    import ast

    from fmus.export.bundle import ROOT, bundle_name

    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            assert not node.level, "bundled code imports absolutely (the bundle rewrites absolute imports)"
            module = (node.module or "").removeprefix(f"{bundle_name()}.")
            if module != "fmus" and not module.startswith("fmus."):
                continue
            below = module.removeprefix("fmus").removeprefix(".")
            found.add(below)
            for alias in node.names:     # a submodule imported by name
                name = f"{below}.{alias.name}".lstrip(".")
                if (ROOT / "fmus" / f"{name.replace('.', '/')}.py").exists() or (ROOT / "fmus" / name.replace(".", "/")).is_dir():
                    found.add(name)
    return found


def test_the_fmu_bundles_every_fmus_module_it_imports(exported):
    """An importer's Python has no parcosim: every ``fmus`` module the bundled code imports
    must travel in the FMU (in this process the repository's would hide a missing one)."""
    import zipfile

    from fmus.export.bundle import bundle_name

    _, _, path = exported
    base = f"resources/{bundle_name()}/fmus/"
    with zipfile.ZipFile(path) as z:
        sources = {name[len(base):]: z.read(name).decode() for name in z.namelist()
                   if name.startswith(base) and name.endswith(".py")}
    bundled = {name[:-3].removesuffix("__init__").rstrip("/").replace("/", ".") for name in sources}
    # fmus.export.build: only the master's "fmu" mode imports it (a system FMU runs in process);
    # fmus.moved: only where the package is called "fmus", never inside a bundle.
    needed = set().union(*(_imports_of(text) for text in sources.values())) - {"export.build", "moved"}
    assert {"slave.base", "cosim.master", "systemfmu.cores", "slave.budget"} <= needed   # the reader reads
    assert needed <= bundled, f"imported but not in the FMU: {sorted(needed - bundled)}"
