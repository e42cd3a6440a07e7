"""The package for Jacobi masters (scenarios.package, fmus.embedded.ChainCore): a control
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

from fmus.embedded import ChainCore, chain_interface
from fmus.master import InProcessInstance, simulate
from scenarios.metrics import rms_norm
from scenarios.package import CONTROL, PLANT, package_scene
from scenarios.scenes import Fidelity, bench, drives_in_plant, get_scene


def _short(scene, stop):
    return dataclasses.replace(scene, system=dataclasses.replace(scene.system, stop_time=stop))


def jacobi_package_run(package, plant_parameters=None, zero_first_inputs=False, correct=True):
    """The package stepped as a Jacobi master steps it, in process: (x, y, x_d, y_d, chain).

    Both instances read what the other held at the step's start; ``zero_first_inputs``
    feeds the plant zeros on the first step, as fmpy's SSP runner does.
    """
    chain = ChainCore(package.chain, PLANT)
    if not correct:
        chain.model.slave.correct = lambda *args: False
    component = package.system.component(PLANT)
    plant = InProcessInstance(component.model, PLANT)
    measured = [c.source.split(".")[1] for c in package.system.connections if c.source.startswith(f"{PLANT}.")]
    commands = [c.target.split(".")[1] for c in package.system.connections if c.target.startswith(f"{PLANT}.")]
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
    return np.array(rows).T, chain


def _tracking(x, y, x_d, y_d, h, window=(1.0, 2.0)):
    t = np.arange(len(x)) * h
    w = (t >= window[0] - 1e-9) & (t <= window[1] + 1e-9)
    return rms_norm(x_d[w] - x[w], y_d[w] - y[w])


def test_package_shape():
    """Two instances, the plant named ``plant`` with its x, y; only measurements and commands
    cross; the bench's drives are inside the plant, driven in voltage mode."""
    package = package_scene(get_scene("bench_circle_TCMDx"))
    system = package.system
    assert [c.name for c in system.components] == [CONTROL, PLANT]
    assert system.component(PLANT).model == "ActuatedFiveBarPlant"
    assert system.component(PLANT).parameters["mode"] == "voltage"
    links = {(c.source, c.target) for c in system.connections}
    assert links == {("plant.q1_enc", "control.q1_enc"), ("plant.q2_enc", "control.q2_enc"),
                     ("control.v_ref1", "plant.v_ref1"), ("control.v_ref2", "plant.v_ref2")}
    assert package.scene.columns["x"] == "plant.x" and package.scene.columns["x_d"] == "control.traj.x_d"
    thesis = package_scene(get_scene("thesis_sim_circle"))
    assert chain_interface(thesis.chain) == (("q1", "q2", "dq1", "dq2"),
                                             {"tau1": "ctrl.tau1", "tau2": "ctrl.tau2"})


@pytest.mark.parametrize("name", ["thesis_sim_circle", "bench_circle_TCMDx"])
def test_chain_one_step_ahead_is_the_masters_loop(name):
    """With its model equal to the plant, the Jacobi-stepped package is the Gauss-Seidel
    master's run of the same physics bit for bit (the bench: its drives in the plant), and
    the measurement never corrects the model."""
    scene = _short(get_scene(name), 0.5)
    (x, y, x_d, y_d), chain = jacobi_package_run(package_scene(scene))
    same_physics = drives_in_plant(scene) if name.startswith("bench") else scene
    master = simulate(same_physics.system)
    assert chain.corrections == 0
    assert np.array_equal(x, master["plant.x"]) and np.array_equal(y, master["plant.y"])
    assert np.array_equal(x_d, master["traj.x_d"])


def test_zero_first_inputs_cost_one_step_of_command():
    """fmpy's runner gives the plant 0 V on the first step: the chain corrects its model
    from the measurement and the tracking over [1, 2] s stays within 1 % of the master's."""
    scene = _short(get_scene("bench_circle_TCMDx"), 2.0)
    (x, y, x_d, y_d), chain = jacobi_package_run(package_scene(scene), zero_first_inputs=True)
    master = simulate(scene.system)
    ours = _tracking(master["plant.x"], master["plant.y"], master["traj.x_d"], master["traj.y_d"], 1e-3)
    assert chain.corrections > 0
    assert abs(_tracking(x, y, x_d, y_d, 1e-3) / ours - 1.0) < 0.01


def test_a_plant_unlike_the_model_stays_under_control():
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
    (x, y, x_d, y_d), _ = jacobi_package_run(package_scene(nominal), {"m0": 0.04}, correct=False)
    assert _tracking(x, y, x_d, y_d, 1e-3) > 3.0 * ours
