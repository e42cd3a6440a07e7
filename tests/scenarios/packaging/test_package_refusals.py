"""scenarios/packaging/chain.py's fast part (its runs through the tools are of the slow kind): the
scenes the default package cannot hold are refused naming the scene and what to do instead,
and a short Jacobi run of the package in process is the Gauss-Seidel master's run of the scene
bit for bit, at the scene's 1 ms and at 2 ms (issue 31: the scenarios' weakest area; a second
sample time; an independent formulation: the master's loop)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fmus.cosim.master import simulate
from scenarios.packaging.chain import package_scene, run_jacobi
from scenarios.scenes import get_scene
from scenarios.scenes.transforms import with_sample_time


def _short(scene, stop):
    return dataclasses.replace(scene, system=dataclasses.replace(scene.system, stop_time=stop))


def _with_component(scene, which, **changes):
    system = scene.system
    components = tuple(dataclasses.replace(c, **changes) if c.name == which else c for c in system.components)
    return dataclasses.replace(scene, system=dataclasses.replace(system, components=components))


def test_scenes_the_default_package_cannot_hold_are_refused_naming_what_to_do():
    """Catches a foreign plant, a plant other than the 5R, or a multi-rate component let
    through, and a refusal that does not name the scene."""
    scene = get_scene("bench_circle_TCMDx")
    with pytest.raises(ValueError, match=r"^scene bench_circle_TCMDx: the plant is an FMU file \(/x/plant\.fmu\); "):
        package_scene(_with_component(scene, "plant", model="/x/plant.fmu"))
    with pytest.raises(ValueError, match=r"^scene bench_circle_TCMDx: the default package \(control chain \+ plant\) "
                                         r"is made for the 5R plant \(a FiveBarPlant named 'plant'\)"):
        package_scene(_with_component(scene, "plant", model="WheeledPendulum"))
    with pytest.raises(ValueError, match=r"^scene bench_circle_TCMDx: multi-rate components cannot be packaged "
                                         r"\(substeps = 1 needed\)$"):
        package_scene(_with_component(scene, "drive1", substeps=2))


@pytest.mark.parametrize("sample_time, dx0", [(None, 0.0), (2e-3, 1e-3)])
def test_the_package_stepped_jacobi_one_step_ahead_is_the_masters_run(sample_time, dx0):
    """With the sample of t = 0 commanding the first step (``zero_start=False``) the package
    stepped as a Jacobi master steps it is the Gauss-Seidel master's run of the scene, bit for
    bit, and the chain's model never needs correcting.  Catches a measurement or command
    wired to another signal, the plant's parameters not the scene's (a start moved by 1 mm), and a
    step of another length than the system's."""
    scene = _short(get_scene("thesis_sim_circle"), 0.06)
    if dx0:                 # the plant's own parameters off their defaults: the start 1 mm to the side
        plant = scene.system.component("plant")
        scene = _with_component(scene, "plant", parameters={**plant.parameters, "x0": plant.parameters["x0"] + dx0})
    if sample_time is not None:
        scene = with_sample_time(scene, sample_time)
    run = run_jacobi(package_scene(scene), zero_start=False)
    master = simulate(scene.system)
    assert run.chain.corrections == 0 and len(run.x) == len(master["plant.x"])
    assert np.array_equal(run.time, master.time)
    assert np.array_equal(run.x, master["plant.x"]) and np.array_equal(run.y, master["plant.y"])
    assert np.array_equal(run.x_d, master["traj.x_d"]) and np.array_equal(run.y_d, master["traj.y_d"])


def test_by_default_the_first_step_is_commanded_zero_whatever_the_master_feeds_first():
    """``zero_start`` is on unless asked off: the short run with fmpy's zeros on the first step and
    the one with the initial outputs are the same bit for bit and never correct the model, and
    both differ from the run whose first step the sample of t = 0 commands (``zero_start=False``).
    Catches ``zero_start`` taken from another option or its default turned off (training 4244 [11];
    the slow test_package.py runs 2 s of two scenes for the same property)."""
    package = package_scene(_short(get_scene("thesis_sim_circle"), 0.03))
    fed_zeros, fed_outputs = (run_jacobi(package, zero_first_inputs=z) for z in (True, False))
    assert fed_zeros.chain.corrections == fed_outputs.chain.corrections == 0
    assert np.array_equal(fed_zeros.x, fed_outputs.x) and np.array_equal(fed_zeros.y, fed_outputs.y)
    commanded = run_jacobi(package, zero_start=False)
    assert not np.array_equal(commanded.x, fed_outputs.x)
