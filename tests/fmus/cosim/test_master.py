"""The master: stepping order, couplings, back ends, multi-rate, errors."""
from dataclasses import replace

import numpy as np
import pytest

from controller.derivators import DEFAULT_FC_ACC, DEFAULT_FC_VEL, SAMPLE_TIME, Derivator
from fmus.cosim.master import AlgebraicLoopError, simulate
from fmus.cosim.system import Component, Connection, System
from plant import PlantSimulator, get_preset
from scenarios.scenes.catalogue import get_scene


def _short(scene_name, stop_time):
    return replace(get_scene(scene_name).system, stop_time=stop_time)


def test_bench_order_keeps_every_sample_in_its_step():
    """Catches a stepping order in which a sampled output is read a step late or a continuous one a step early."""
    result = simulate(_short("bench_circle_TCMDx", 0.0))
    position = {name: i for i, name in enumerate(result.order)}
    # sampled outputs are read in the step that produced them ...
    for before, after in (("deriv", "ctrl"), ("deriv", "obs1"), ("obs1", "drive1"), ("obs2", "drive2"),
                          ("ctrl", "drive1"), ("ctrl", "drive2")):
        assert position[before] < position[after]
    # ... and continuous outputs at the step's start by the sampled components
    for reader in ("deriv", "ctrl"):
        assert position[reader] < position["plant"]
    assert position["ctrl"] < position["traj"]


def test_thesis_scene_order_controller_first():
    """Catches a stepping order for the thesis scene other than controller, trajectory, plant."""
    assert simulate(_short("thesis_sim_circle", 0.0)).order == ("ctrl", "traj", "plant")


def _derivator_outputs(inputs1, inputs2):
    """An independent run of the model derivator over given input samples."""
    d = Derivator(DEFAULT_FC_VEL, DEFAULT_FC_ACC, SAMPLE_TIME)
    d.reset([inputs1[0], inputs2[0]])
    return np.array([d.step([a, b])[0][0] for a, b in zip(inputs1, inputs2)])


def _two_derivators(stop_time=0.05, extra=()):
    """traj -> d1 -> d2: d2 differentiates d1's velocity estimates (both sampled)."""
    components = (Component("traj", "Trajectory", {"kind": "thesis_circle"}),
                  Component("d1", "Derivator", {}), Component("d2", "Derivator", {}))
    connections = (Connection("traj.x_d", "d1.q1"), Connection("traj.y_d", "d1.q2"),
                   Connection("d1.dq1", "d2.q1"), Connection("d1.dq2", "d2.q2")) + tuple(extra)
    return System(components, connections, ("d1.dq1", "d1.dq2", "d2.dq1", "traj.x_d"), stop_time=stop_time)


def test_gauss_seidel_passes_samples_within_the_step_jacobi_one_step_later():
    """Catches couplings that swap Gauss-Seidel and Jacobi, or pass values one step off."""
    gs = simulate(_two_derivators(), coupling="gauss-seidel")
    jacobi = simulate(_two_derivators(), coupling="jacobi")
    # traj -> d1: both couplings read the trajectory's value at the step's start
    assert np.array_equal(gs["d1.dq1"], jacobi["d1.dq1"])
    u1, u2 = gs["d1.dq1"], gs["d1.dq2"]   # row 0: initial outputs (0), row k + 1: step k
    # Gauss-Seidel: d2's step k reads d1's sample of step k
    assert np.allclose(gs["d2.dq1"][1:], _derivator_outputs(u1[1:], u2[1:]), rtol=1e-12, atol=1e-12)
    # Jacobi: d2's step k reads what d1 held at the step's start (its step k - 1)
    assert np.allclose(jacobi["d2.dq1"][1:], _derivator_outputs(u1[:-1], u2[:-1]), rtol=1e-12, atol=1e-12)
    assert not np.allclose(gs["d2.dq1"], jacobi["d2.dq1"])


def test_sampled_loop_is_reported_as_algebraic_loop():
    """Catches a master that runs a loop of sampled feedthroughs instead of naming it."""
    system = _two_derivators()
    system = replace(system, connections=tuple(c for c in system.connections if c.source != "traj.y_d")
                     + (Connection("d2.dq2", "d1.q2"),))
    with pytest.raises(AlgebraicLoopError, match=r"d1\.dq2 -> d2\.q2|d2\.dq2 -> d1\.q2"):
        simulate(system)


@pytest.mark.parametrize("coupling", ["gauss-seidel", "jacobi"])
def test_fmu_and_inprocess_identical(coupling, built_fmus):
    """Catches an FMU run whose rows differ from the in-process run by a bit, with either coupling."""
    system = _short("bench_triangle_PDMDq", 0.15)
    fmu_dir = next(iter(built_fmus.values())).parent
    a = simulate(system, mode="inprocess", coupling=coupling)
    b = simulate(system, mode="fmu", coupling=coupling, fmu_dir=fmu_dir)
    assert a.error is None and b.error is None and a.order == b.order
    for signal in system.record:
        assert np.array_equal(a[signal], b[signal]), signal


def _plant_only(torque, stop_time, substeps=1):
    components = (Component("plant", "FiveBarPlant", {"preset": "bench", "x0": -0.002, "y0": 0.108,
                                                      "tau1": torque, "tau2": -torque}, substeps=substeps),)
    return System(components, (), ("plant.x", "plant.y", "plant.q1"), stop_time=stop_time)


def test_multirate_substeps_equal_the_plant_stepped_finer():
    """Catches multi-rate sub-steps with a wrong time or step size (the plant stepped at h / 4 by hand)."""
    result = simulate(_plant_only(0.01, 0.05, substeps=4))
    sim = PlantSimulator(get_preset("bench"), -0.002, 0.108)
    x = [sim.outputs()["x"]]
    for k in range(50):
        for j in range(4):
            sim.time = k * 1e-3 + j * 0.25e-3
            sim.step(0.01, -0.01, 0.25e-3)
        x.append(sim.outputs()["x"])
    assert np.array_equal(result["plant.x"], np.array(x))


@pytest.mark.parametrize("mode", ["inprocess", "fmu"])
def test_refused_step_stops_the_run_and_keeps_the_record(mode, built_fmus):
    # 0.3 N m open loop throws the bench mechanism into a singular pose within the second.
    """Catches a refused step that crashes the run, loses its rows or its message."""
    system = _plant_only(0.3, 2.0)
    result = simulate(system, mode=mode, fmu_dir=next(iter(built_fmus.values())).parent)
    assert result.error is not None and str(result.error).startswith("plant refused the step from t = ")
    assert "singular" in str(result.error) and result.error.reason == "singular"
    n = len(result.time)
    assert 10 < n < system.steps + 1
    assert np.all(np.isfinite(result["plant.x"]))
    assert result.time[-1] < result.error.time + 1.5e-3


def test_bad_systems_are_refused_before_running():
    """Catches a master that starts a system with an unknown variable, parameter or mode."""
    good = _plant_only(0.0, 0.01)
    with pytest.raises(ValueError, match="no variable 'z'"):
        simulate(replace(good, record=("plant.z",)))
    with pytest.raises(ValueError, match="no parameter 'colour'"):
        simulate(replace(good, components=(Component("plant", "FiveBarPlant", {"colour": 1.0}),)))
    with pytest.raises(ValueError, match="mode"):
        simulate(good, mode="gpu")
    with pytest.raises(ValueError, match="names no component"):
        System(good.components, (Connection("ctrl.tau1", "plant.tau1"),), (), 0.1)
    with pytest.raises(ValueError, match="connected more than once"):
        System(good.components, (Connection("plant.x", "plant.tau1"), Connection("plant.y", "plant.tau1")),
               (), 0.1)


def _drives_and_plant(substeps, stop_time=0.2):
    components = (Component("drive1", "DCMotorDrive", {"preset": "motor1", "mode": "voltage", "v_ref": 3.0},
                            substeps=substeps),
                  Component("drive2", "DCMotorDrive", {"preset": "motor2", "mode": "voltage", "v_ref": -3.0},
                            substeps=substeps),
                  Component("plant", "FiveBarPlant", {"preset": "bench", "x0": -0.002, "y0": 0.108},
                            substeps=substeps))
    connections = (Connection("drive1.tau", "plant.tau1"), Connection("drive2.tau", "plant.tau2"),
                   Connection("plant.dq1", "drive1.omega"), Connection("plant.dq2", "drive2.omega"))
    return System(components, connections, ("plant.x", "plant.y"), stop_time=stop_time)


def test_group_substeps_converge_on_the_coupled_drive_plant_motion():
    """Catches group sub-steps that do not converge at first order on the drive-plant motion."""
    runs = {n: simulate(_drives_and_plant(n)) for n in (1, 2, 4, 8)}
    for r in runs.values():
        assert r.error is None
    gap = {n: np.max(np.hypot(runs[n]["plant.x"] - runs[2 * n]["plant.x"],
                              runs[n]["plant.y"] - runs[2 * n]["plant.y"])) for n in (1, 2, 4)}
    # explicit coupling is first order in the exchange step: each halving about halves the gap
    assert gap[1] > 1e-7
    assert 1.5 < gap[1] / gap[2] < 3.0 and 1.5 < gap[2] / gap[4] < 3.0


def test_mean_drive_torque_couples_the_plant_better_than_the_end_torque():
    """Catches a mean drive torque that is not the step's mean (it would not beat the end torque)."""
    def torque_output(system, mode):
        return replace(system, components=tuple(
            replace(c, parameters={**c.parameters, "torque_output": mode}) if c.model == "DCMotorDrive" else c
            for c in system.components))

    fine = simulate(_drives_and_plant(32))
    for n in (1, 4):
        gap = {mode: np.max(np.hypot(*(simulate(torque_output(_drives_and_plant(n), mode))[s] - fine[s]
                                        for s in ("plant.x", "plant.y"))))
               for mode in ("end", "mean")}
        assert gap["mean"] < 0.5 * gap["end"]
