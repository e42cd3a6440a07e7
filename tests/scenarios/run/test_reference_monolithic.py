"""The monolithic reference (scenarios/reference.py) on long runs: its convergence, its
sample-by-sample semantics (its model pieces and short runs: test_reference_samples.py), and the
co-simulation measured against it.

Numbers are printed (``pytest -s``); asserted are only properties that hold by construction:
convergence of the reference itself, the ``cosim`` coupling reproducing the master up to the
plant's RK4 error (smaller with more RK4 substeps), and the master's deviation from the
reference being the coupling's (plant substeps cannot reduce it).
"""
from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim.master import simulate
from motor import CurrentController, get_motor_preset, shaft_torque
from scenarios.reference import ReferenceError, deviation, reference_run, with_parameters
from scenarios.scenes.catalogue import get_scene

pytestmark = [pytest.mark.slow]

BENCH = "bench_circle_TCMDx"
THESIS = "thesis_sim_circle"
SHORT = 0.3


def _system(name, stop_time, changes=lambda s: s):
    return changes(replace(get_scene(name).system, stop_time=stop_time))


@pytest.fixture(scope="module")
def bench_runs():
    """The short bench run: reference, its tighter reruns, the cosim-coupled reference, the master."""
    system = _system(BENCH, SHORT)
    return {
        "ref": reference_run(system),
        "ref/2": reference_run(system, rtol=5e-11, atol=5e-14),
        "ref/10": reference_run(system, rtol=1e-11, atol=1e-14),
        "cosim": reference_run(system, coupling="cosim"),
        "master": simulate(system),
        "master_rk4x4": simulate(with_parameters(system, "plant", substeps=4)),
    }


# --- convergence ------------------------------------------------------------------------------

def test_bench_reference_converges(bench_runs):
    """Catches a bench reference that changes when its tolerances are tightened (not converged)."""
    ref = bench_runs["ref"]
    assert ref.completed, ref.error
    for key in ("ref/2", "ref/10"):
        d = deviation(bench_runs[key], ref)
        print(f"\n{BENCH} 0-{SHORT} s, reference at rtol, atol {key[3:]}: max {d['max']:.2e} m")
        assert d["max"] < 1e-9
        for drive in ("drive1", "drive2"):
            assert np.max(np.abs(bench_runs[key][f"{drive}.i"] - ref[f"{drive}.i"])) < 1e-6


def test_thesis_reference_converges():
    """Catches a thesis reference that changes when its tolerances are tightened (not converged)."""
    system = _system(THESIS, SHORT)
    ref = reference_run(system)
    for factor in (2, 10):
        d = deviation(reference_run(system, rtol=1e-10 / factor, atol=1e-13 / factor), ref)
        print(f"\n{THESIS} 0-{SHORT} s, reference at {factor}x tighter tolerances: max {d['max']:.2e} m")
        assert d["max"] < 1e-9


# --- the reference samples as the master does ---------------------------------------------------

def test_cosim_coupling_reproduces_the_master(bench_runs):
    """Same slaves, same order, same explicit drive/plant coupling: only the plant's RK4 differs."""
    rk4 = deviation(bench_runs["master"], bench_runs["cosim"])
    rk4x4 = deviation(bench_runs["master_rk4x4"], bench_runs["cosim"])
    print(f"\nmaster - reference(cosim coupling), {BENCH} 0-{SHORT} s: RK4 1 substep max {rk4['max']:.2e} m, "
          f"4 substeps {rk4x4['max']:.2e} m")
    assert rk4["max"] < 1e-9
    assert rk4x4["max"] < rk4["max"]


def test_monolithic_samples_in_gauss_seidel_order(bench_runs):
    """Row k + 1 holds the samples taken at t_k: the drive's voltage is K(z) on the controller's
    i_ref and the observer's i_hat of that same sample; the observer used the voltage of the
    previous interval and the derivator's speed at t_k; the shaft torque is B.2 of the state."""
    ref = bench_runs["ref"]
    drive = 1
    p = get_motor_preset("motor1")
    from motor import design_current_controller

    controller = CurrentController(design_current_controller(p), p.v_max)
    i_ref, i_hat, v = ref["ctrl.i_ref1"], ref["obs1.i_hat"], ref["drive1.v"]
    expected = [controller.update(a, b) for a, b in zip(i_ref[1:], i_hat[1:])]
    assert np.allclose(v[1:], expected, rtol=0, atol=1e-12)
    assert np.allclose(i_hat[1:], (v[:-1] - p.ke * ref["deriv.dq1"][1:]) / p.R, rtol=0, atol=1e-12)
    torque = [shaft_torque(i, w, p) for i, w in zip(ref[f"drive{drive}.i"], ref["plant.dq1"])]
    assert np.allclose(ref["drive1.tau"], torque, rtol=0, atol=1e-15)
    assert abs(v).max() > 1.0   # the loop did something


def test_thesis_sim_reference_agrees_with_the_master():
    """Ideal actuators: no coupling to get wrong, only the plant's RK4 at 1 ms."""
    system = _system(THESIS, 0.5)
    ref = reference_run(system)
    rk4 = deviation(simulate(system), ref)
    rk4x4 = deviation(simulate(with_parameters(system, "plant", substeps=4)), ref)
    print(f"\nmaster - reference, {THESIS} 0-0.5 s: RK4 1 substep max {rk4['max']:.2e} m "
          f"(rms {rk4['rms']:.2e}), 4 substeps max {rk4x4['max']:.2e} m")
    assert rk4["max"] < 1e-9
    assert rk4x4["max"] < rk4["max"]


# --- the co-simulation measured against the reference ------------------------------------------

def test_bench_cosimulation_deviation_is_the_coupling():
    """Printed: the master's deviation at the defaults.  Asserted: it is the drive/plant coupling's
    (the reference with the co-simulation's coupling shows the same deviation), so refining the
    plant's integration leaves it unchanged."""
    stop = 2.0
    system = _system(BENCH, stop)
    ref = reference_run(system)
    cosim = reference_run(system, coupling="cosim")
    master = simulate(system)
    master_x4 = simulate(with_parameters(system, "plant", substeps=4))
    d = deviation(master, ref)
    coupling = deviation(cosim, ref)
    d_x4 = deviation(master_x4, ref)
    print(f"\nmaster - reference, {BENCH} 0-{stop:g} s (reference {ref.wall_s:.1f} s wall): "
          f"rms {d['rms']:.2e} m, max {d['max']:.2e} m at t = {d['t_max']:.3f} s; "
          f"from 0.1 s on: rms {deviation(master, ref, 0.1)['rms']:.2e} m; "
          f"coupling alone: rms {coupling['rms']:.2e} m; plant RK4 x4: rms {d_x4['rms']:.2e} m")
    assert master.completed and ref.completed and cosim.completed
    assert abs(d["rms"] - coupling["rms"]) < 1e-9
    assert abs(d_x4["rms"] - d["rms"]) < 1e-9


# --- the bench twin: the drive's own effects in the reference ----------------------------------

TWIN = "bench_real_circle_TCMDq"


def _drives_changed(**changes):
    """``System -> System`` setting each drive's parameters; a callable value maps the old one."""
    def change(system):
        for c in system.components:
            if c.model == "DCMotorDrive":
                system = with_parameters(system, c.name, **{k: v(c.parameters[k]) if callable(v) else v
                                                            for k, v in changes.items()})
        return system
    return change


@pytest.fixture(scope="module")
def twin_runs():
    system = _system(TWIN, SHORT)
    return {"system": system, "ref": reference_run(system), "master": simulate(system),
            "cosim": reference_run(system, coupling="cosim")}


def test_the_twins_reference_moves_with_the_drives_stiction_and_imperfections(twin_runs):
    """The reference steps the drive's own model: three times the stiction, or the drive's effects
    (LuGre, PWM, current noise and offset) off, move the end effector far more than the
    co-simulation's coupling error (a reference that dropped them gave identical rows)."""
    ref, coupling = twin_runs["ref"], deviation(twin_runs["master"], twin_runs["ref"])
    stiction = deviation(reference_run(twin_runs["system"], system_changes=_drives_changed(mu_s=lambda v: 3 * v)), ref)
    ideal = deviation(reference_run(twin_runs["system"], system_changes=_drives_changed(
        friction="tanh", pwm_counts=0, current_noise=0.0, current_offset=0.0)), ref)
    print(f"\n{TWIN} 0-{SHORT} s, reference moved by mu_s x3: max {stiction['max']:.2e} m, by the drive's effects "
          f"off: max {ideal['max']:.2e} m; master - reference max {coupling['max']:.2e} m")
    assert stiction["max"] > 10 * coupling["max"]
    assert ideal["max"] > 10 * coupling["max"]


def test_the_twins_reference_samples_the_drives_pwm_voltage(twin_runs):
    """Each drive's voltage is its own sample (Drive.sample_voltage): a multiple of the PWM
    quantum v_max / pwm_counts, the controller's unquantised output being kept inside."""
    system, ref = twin_runs["system"], twin_runs["ref"]
    for name in ("drive1", "drive2"):
        c = system.component(name)
        quantum = get_motor_preset(c.parameters["preset"]).v_max / c.parameters["pwm_counts"]
        steps = ref[f"{name}.v"] / quantum
        assert np.max(np.abs(steps - np.round(steps))) < 1e-9
        assert np.abs(steps).max() > 10


def test_the_twins_cosimulation_is_its_reference_up_to_the_coupling(twin_runs):
    """The reference with the co-simulation's explicit coupling reproduces the master up to the
    plant's RK4 error (every discrete part, the drives' included, is the same code); the
    monolithic reference differs by the coupling error only (printed)."""
    master, ref = twin_runs["master"], twin_runs["ref"]
    d = deviation(master, ref)
    print(f"\nmaster - reference, {TWIN} 0-{SHORT} s: rms {d['rms']:.2e} m, max {d['max']:.2e} m at "
          f"t = {d['t_max']:.3f} s")
    assert deviation(master, twin_runs["cosim"])["max"] < 1e-9
    assert d["rms"] < 3e-5


def test_a_component_refusing_its_initialisation_is_named():
    """A drive whose parameters its model refuses (LuGre needs mu > 0): the reference says
    which component and why, rather than failing later on a model that was never built."""
    with pytest.raises(ReferenceError, match=r"drive1: initialisation refused: LuGre friction: Fc \(mu\) = 0.0"):
        reference_run(TWIN, stop_time=0.01, system_changes=_drives_changed(mu=0.0))
