"""The package for Jacobi masters (scenarios.packaging.chain, fmus.systemfmu.cores.ChainCore): a control
chain FMU one sample ahead and the plant FMU.

What a user sees is checked in the tools themselves (test_tools.py); here, in process:
the chain's one-step-ahead bookkeeping reproduces the master's loop bit for bit when its
model is the plant, and its measurement correction keeps the loop closed on a plant that
differs from the model.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fmus.systemfmu.cores import chain_interface
from fmus.cosim.master import simulate
from scenarios.run.metrics import rms_norm
from scenarios.packaging.chain import CONTROL, PLANT, package_scene, run_jacobi
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.thesis import Fidelity, bench
from scenarios.scenes.transforms import drives_in_plant

pytestmark = [pytest.mark.slow, pytest.mark.fmu]


def _short(scene, stop):
    return dataclasses.replace(scene, system=dataclasses.replace(scene.system, stop_time=stop))


def jacobi_package_run(package, plant_parameters=None, zero_first_inputs=False, zero_start=True):
    """:func:`scenarios.packaging.chain.run_jacobi` as ((x, y, x_d, y_d), chain)."""
    run = run_jacobi(package, plant_parameters, zero_first_inputs, zero_start)
    return (run.x, run.y, run.x_d, run.y_d), run.chain


def _tracking(x, y, x_d, y_d, h, window=(1.0, 2.0)):
    t = np.arange(len(x)) * h
    w = (t >= window[0] - 1e-9) & (t <= window[1] + 1e-9)
    return rms_norm(x_d[w] - x[w], y_d[w] - y[w])


def test_package_shape():
    """Two instances, the plant named ``plant`` with its x, y; only measurements and commands
    cross: the drives' torques to the plant, its encoder angles and shaft speeds back."""
    package = package_scene(get_scene("bench_circle_TCMDx"))
    system = package.system
    assert [c.name for c in system.components] == [CONTROL, PLANT]
    assert system.component(PLANT).model == "FiveBarPlant"
    links = {(c.source, c.target) for c in system.connections}
    assert links == {("plant.q1_enc", "control.q1_enc"), ("plant.q2_enc", "control.q2_enc"),
                     ("plant.dq1", "control.dq1"), ("plant.dq2", "control.dq2"),
                     ("control.tau1", "plant.tau1"), ("control.tau2", "plant.tau2")}
    assert package.scene.columns["x"] == "plant.x" and package.scene.columns["x_d"] == "control.traj.x_d"
    assert package.scene.columns["i1"] == "control.drive1.i"
    thesis = package_scene(get_scene("thesis_sim_circle"))
    assert chain_interface(thesis.chain) == (("q1", "q2", "dq1", "dq2"),
                                             {"tau1": "ctrl.tau1", "tau2": "ctrl.tau2"})
    in_plant = package_scene(drives_in_plant(get_scene("bench_circle_TCMDx"), substeps=8)).system
    assert in_plant.component(PLANT).parameters["mode"] == "voltage"
    assert {c.target for c in in_plant.connections} >= {"plant.v_ref1", "plant.v_ref2"}


@pytest.mark.parametrize("name", ["thesis_sim_circle", "bench_circle_TCMDx", "bench_circle_TCMDx in plant"])
def test_chain_one_step_ahead_is_the_masters_loop(name):
    """With its model equal to the plant and the sample of t = 0 commanding the first step
    (``zero_start=False``, for masters that pass the outputs after initialisation), the
    Jacobi-stepped package is the Gauss-Seidel master's run of the scene bit for bit (also
    with the drives in the plant), and the measurement never corrects the model."""
    scene = _short(get_scene(name.split()[0]), 0.5)
    if name.endswith("in plant"):
        scene = drives_in_plant(scene, substeps=8)
    (x, y, x_d, y_d), chain = jacobi_package_run(package_scene(scene), zero_start=False)
    master = simulate(scene.system)
    assert chain.corrections == 0
    assert np.array_equal(x, master["plant.x"]) and np.array_equal(y, master["plant.y"])
    assert np.array_equal(x_d, master["traj.x_d"])


@pytest.mark.parametrize("name", ["thesis_sim_circle", "bench_circle_TCMDx"])
def test_zero_start_is_the_same_run_whatever_the_master_feeds_first(name):
    """With ``zero_start`` (the default) the first step is commanded zero in the plant and
    in the model: fmpy's zeros on the first step and Ecos' initial outputs give the same
    run bit for bit, the model never needs correcting, and the tracking over [1, 2] s is
    the master's within 0.5 %.  Without it, fmpy's zeros leave the model off the plant
    and the measurement has to correct it again and again."""
    scene = _short(get_scene(name), 2.0)
    (x, y, x_d, y_d), chain = jacobi_package_run(package_scene(scene), zero_first_inputs=True)
    (x2, y2, _, _), chain2 = jacobi_package_run(package_scene(scene), zero_first_inputs=False)
    assert chain.corrections == chain2.corrections == 0
    assert np.array_equal(x, x2) and np.array_equal(y, y2)
    master = simulate(scene.system)
    ours = _tracking(master["plant.x"], master["plant.y"], master["traj.x_d"], master["traj.y_d"], 1e-3)
    assert abs(_tracking(x, y, x_d, y_d, 1e-3) / ours - 1.0) < 0.005
    _, fed_zeros = jacobi_package_run(package_scene(scene), zero_first_inputs=True, zero_start=False)
    assert fed_zeros.corrections > 0


def test_a_plant_unlike_the_model_stays_under_control(monkeypatch):
    """A 40 g payload the chain's model does not have: the measurement corrects the model,
    and the loop tracks as the master's loop with the same plant (whose controller does not
    know the payload either), within 5 %.  Without the correction the chain controls its own
    model and the real plant runs open loop, many times worse."""
    stop = 2.0
    nominal = _short(bench("TCMDx", "circle"), stop)
    loaded = _short(bench("TCMDx", "circle", fidelity=Fidelity(m0=0.04)), stop)
    master = simulate(loaded.system)
    ours = _tracking(master["plant.x"], master["plant.y"], master["traj.x_d"], master["traj.y_d"], 1e-3)
    (x, y, x_d, y_d), chain = jacobi_package_run(package_scene(nominal), {"m0": 0.04})
    assert chain.corrections > 50
    assert abs(_tracking(x, y, x_d, y_d, 1e-3) / ours - 1.0) < 0.05
    monkeypatch.setattr("plant.correction.corrected_state", lambda *args: None)   # measurement ignored
    (x, y, x_d, y_d), uncorrected = jacobi_package_run(package_scene(nominal), {"m0": 0.04})
    assert uncorrected.corrections == 0
    assert _tracking(x, y, x_d, y_d, 1e-3) > 3.0 * ours
