"""Cold start (issue 27, item 5): an FMU started with its parameters as built imports what its
model needs and builds nothing; its designs travel in its resources (fmus/slave/designs.py).

Not timed (benchmarks/cold_start.py measures the seconds): these check which packages a
fresh process has loaded after ``fmpy.simulate_fmu`` of our FMUs, and that the designs an FMU
carries are the ones computed in process, bit for bit.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fmus.slave import designs

pytestmark = [pytest.mark.slow, pytest.mark.fmu]

#: Packages an FMU started with its parameters as built must not import (they are for
#: designs computed ahead, plots and the JIT that the C kernels replace).
HEAVY = ("control", "scipy.signal", "matplotlib", "numba")

#: A fresh process: simulate each FMU (argv: "path[|name=value]" ...) for 3 ms, logging on,
#: print the heavy packages loaded after each and the log messages so far.
CHILD = """
import json, sys
from fmpy import simulate_fmu
messages = []
def log(component, instance, status, category, message):
    messages.append(message.decode(errors="replace"))
heavy = %r
for spec in sys.argv[1:]:
    path, _, change = spec.partition("|")
    start = {}
    if change:
        name, value = change.split("=")
        start[name] = float(value)
    simulate_fmu(path, stop_time=0.003, output_interval=1e-3, start_values=start, debug_logging=True, logger=log)
    print(json.dumps({"fmu": spec, "heavy": [h for h in heavy if h in sys.modules], "messages": messages}))
""" % (HEAVY,)


def _run_fresh(specs, tmp_path) -> list:
    """Each spec's line of :data:`CHILD`, run in a fresh process with empty caches, outside
    the repository (nothing of parcosim imported but the FMUs' bundles)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    for name in ("HOME", "XDG_CACHE_HOME", "PARCOSIM_CACHE", "NUMBA_CACHE_DIR", "PARCOSIM_COMPILED_CACHE",
                 "MPLCONFIGDIR"):
        env[name] = str(tmp_path / name.lower())
        os.makedirs(env[name])
    done = subprocess.run([sys.executable, "-c", CHILD, *map(str, specs)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]


@pytest.fixture(scope="module")
def closed_loop(tmp_path_factory):
    from fmus.systemfmu.export import export_fmu
    from scenarios.scenes.catalogue import get_scene

    return export_fmu(get_scene("bench_circle_TCMDx").system, tmp_path_factory.mktemp("loop") / "ClosedLoop.fmu")


@pytest.fixture(scope="module")
def fresh_runs(built_fmus, closed_loop, tmp_path_factory):
    """One fresh process that runs, in turn, the FMUs whose initialisation computes designs
    (and the plant), a copy of the drive with motor 2 baked in (as an SSP package's), then the
    drive with another resistance and the controller with another grid: {spec: line}."""
    from fmus.systemfmu.export import with_start_values

    baked = with_start_values(built_fmus["DCMotorDrive"], {"preset": "motor2"},
                              tmp_path_factory.mktemp("baked") / "BakedDrive.fmu")
    specs = [built_fmus["FiveBarPlant"], built_fmus["Derivator"], built_fmus["DCMotorDrive"],
             built_fmus["PositionController"], closed_loop, baked,
             f"{built_fmus['DCMotorDrive']}|R=1.5", f"{built_fmus['PositionController']}|grid_step=0.006"]
    return {Path(line["fmu"].split("|")[0]).stem + line["fmu"].partition("|")[2]: line
            for line in _run_fresh(specs, tmp_path_factory.mktemp("fresh"))}


@pytest.mark.parametrize("package", HEAVY)
def test_an_fmu_started_as_built_does_not_import(fresh_runs, package):
    """Catches an eager import put back: a package ``__init__`` that imports every module, a
    module-level ``import control``, a slave that imports a model it does not run, or an FMU
    whose designs are not in its resources (computed at its start; for the baked copy: the
    designs of its start values, not only the defaults')."""
    for name in ("FiveBarPlant", "Derivator", "DCMotorDrive", "PositionController", "ClosedLoop", "BakedDrive"):
        assert package not in fresh_runs[name]["heavy"], f"{name} imported {package}"


def test_other_parameters_compute_their_designs(fresh_runs):
    """A parameter that changes a design is not served the built one: the drive with another
    R designs its controller (python-control imported then), the controller with another grid
    builds its table and says so in the log; the built table is not announced."""
    assert "control" in fresh_runs["DCMotorDriveR=1.5"]["heavy"]
    assert not any("tabulated model was built" in m for m in fresh_runs["PositionController"]["messages"])
    assert any("tabulated model was built" in m for m in fresh_runs["PositionControllergrid_step=0.006"]["messages"])


def test_designs_travel_bit_for_bit(tmp_path):
    """What :func:`fmus.slave.designs.load` puts back is what was computed: the current controller's
    coefficients and poles, the filters, the table (catches a field mixed up or rounded in
    the file)."""
    from controller import derivators, model
    from controller.position import PositionController
    from controller.strategies import get_strategy
    from motor import Drive, current_controller, motor1
    from plant import get_preset

    def compute():
        drive = Drive(motor1)
        derivator = derivators.Derivator()
        law = PositionController(get_preset("bench"), get_strategy("TCMDx", "circle"), model="tabulated", cache=False)
        return drive.controller.design, derivator.velocity_sos, derivator.acceleration_sos, law.model.table

    with designs.recording() as recorded:
        computed = compute()
        designs.write(recorded(), tmp_path / designs.DESIGNS_FILE)
    with designs.recording():       # empty stores, as in a fresh process
        for m in (current_controller, derivators, model):
            m.RECORDING = False
        assert designs.load(str(tmp_path)) == 4
        loaded = compute()
    design, velocity, acceleration, table = loaded
    assert design.plant is None, "the drive's design was computed again, not loaded"
    for field in ("alpha", "beta", "gamma", "delta", "T"):
        assert getattr(design, field) == getattr(computed[0], field)
    np.testing.assert_array_equal(design.closed_loop_poles, computed[0].closed_loop_poles)
    np.testing.assert_array_equal(velocity, computed[1])
    np.testing.assert_array_equal(acceleration, computed[2])
    np.testing.assert_array_equal(table, computed[3])


def test_a_build_leaves_the_process_computing_its_own_designs(closed_loop):
    """Building an FMU instantiates our slaves here with its resources (to find its designs,
    and in pythonfmu's reading of the model description): the designs it loads or records
    must not stay in this process's modules (catches a design served from a build, without
    its transfer functions, to code that asked to compute it)."""
    from motor import current_controller, motor1

    assert current_controller.design_current_controller(motor1).plant is not None
