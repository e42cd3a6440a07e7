"""Spec-built plants (plant/specsim.py, the SpecPlant FMU of ``parcosim build-plant``): the
shipped 5R specs against FiveBarPlant's two kernels, the balanced 5R, refusals."""
import math

import numpy as np
import pytest
from fmpy.validation import validate_fmu

from fmus.export.specfmu import build_plant_fmu
from plant import IntegratorSettings, PlantSimulator, get_preset
from plant import spec as plant_spec
from plant.parallel import inverse_dynamics_terms
from plant.specsim import AssemblyError, SpecSimulator, assemble
from tests.support.fmi_support import FmuInstance

pytestmark = [pytest.mark.slow]

START = (0.07, 0.17)


def torques(t):
    """The stated torque profile of docs/spec.md [N m]."""
    return 0.02 * math.sin(2 * math.pi * t) + 0.01, -0.015 * math.cos(3 * math.pi * t)


def reference_paths(preset, n_steps):
    """FiveBarPlant's model, both kernels: (x, y) after each 1 ms step."""
    sims = {k: PlantSimulator(get_preset(preset), *START, IntegratorSettings(kernel=k)) for k in ("general", "fast")}
    paths = {k: np.empty((n_steps, 2)) for k in sims}
    for i in range(n_steps):
        for k, sim in sims.items():
            sim.step(*torques(i * 1e-3), 1e-3)
            paths[k][i] = sim.outputs()["x"], sim.outputs()["y"]
    return paths


@pytest.fixture(scope="module")
def bench_fmu(tmp_path_factory):
    return build_plant_fmu("bench_5r", tmp_path_factory.mktemp("spec") / "bench_5r.fmu")


def test_spec_fmu_equals_five_bar_plant_over_one_second(bench_fmu):
    """Catches a SpecPlant FMU that drifts from the FiveBarPlant over one second."""
    assert validate_fmu(str(bench_fmu)) == []
    fmu = FmuInstance(bench_fmu, {"x0": START[0], "y0": START[1]})
    n = 1000
    path = np.empty((n, 2))
    for i in range(n):
        tau1, tau2 = torques(i * 1e-3)
        fmu.step(1e-3, tau1=tau1, tau2=tau2)
        path[i] = fmu.get("x"), fmu.get("y")
    assert fmu.get("residual") < 1e-9
    fmu.close()
    ref = reference_paths("bench", n)
    assert np.linalg.norm(path[-1] - START) > 0.03                      # a real motion
    assert np.max(np.linalg.norm(path - ref["general"], axis=1)) <= 1e-12
    assert np.max(np.linalg.norm(path - ref["fast"], axis=1)) <= 1e-9


def test_thesis_sim_spec_equals_five_bar_plant_in_process():
    """Catches a spec-built 5R that differs from the general algorithm or the fast kernel."""
    sim = SpecSimulator(plant_spec.load("thesis_sim_5r"), (*START, 0.0))
    n = 300
    ref = reference_paths("thesis_sim", n)
    for i in range(n):
        sim.step(torques(i * 1e-3), 1e-3)
        out = sim.outputs()
        assert math.hypot(out["x"] - ref["general"][i, 0], out["y"] - ref["general"][i, 1]) <= 1e-12
        assert math.hypot(out["x"] - ref["fast"][i, 0], out["y"] - ref["fast"][i, 1]) <= 1e-9


def test_spec_fmu_refuses_bad_input_without_crashing(bench_fmu):
    """Catches a SpecPlant FMU that accepts NaN or moves its outputs on a refused step."""
    fmu = FmuInstance(bench_fmu, {"x0": START[0], "y0": START[1]})
    fmu.step(1e-3, tau1=0.01, tau2=0.0)
    x = fmu.get("x")
    error = fmu.refused_step(tau1=float("nan"))
    assert "tau1 = nan" in error and "t = 0.001" in error
    assert fmu.get("x") == x                                            # outputs of the last good step
    fmu.close()
    far = FmuInstance(bench_fmu, {"x0": 0.5, "y0": 0.17})
    assert "initialisation refused" in far.refused_step() and "cannot close the loop" in far.get("error")
    far.close()


def test_balanced_5r_has_no_gravity_load_and_stays_at_rest():
    """Catches balancing counter-masses placed wrong: gravity would load the joints."""
    spec = plant_spec.load("balanced_5r")
    rng = np.random.default_rng(4)
    for _ in range(10):
        x, y = rng.uniform(-0.06, 0.06), rng.uniform(0.12, 0.22)
        q = assemble(spec, (x, y, 0.0))
        dq = np.zeros_like(q)
        terms = inverse_dynamics_terms(spec.mechanism, q, dq)
        assert np.max(np.abs(terms.g)) < 1e-12
    sim = SpecSimulator(spec, (0.03, 0.2, 0.0))
    for _ in range(200):
        sim.step([0.0, 0.0], 1e-3)
    assert math.hypot(sim.outputs()["x"] - 0.03, sim.outputs()["y"] - 0.2) <= 1e-12
    unbalanced = plant_spec.loads(plant_spec.load("thesis_sim_5r").text.replace(
        "gravity = [0.0, 0.0, 0.0]", "gravity = [0.0, -9.81, 0.0]"))
    falls = SpecSimulator(unbalanced, (0.03, 0.2, 0.0))
    for _ in range(50):
        falls.step([0.0, 0.0], 1e-3)
    assert falls.outputs()["y"] < 0.2 - 1e-3


def test_assembly_out_of_reach_is_refused():
    """Catches a spec simulator that starts from a pose whose loop cannot close."""
    with pytest.raises(AssemblyError, match="cannot close the loop"):
        SpecSimulator(plant_spec.load("thesis_sim_5r"), (0.0, 0.4, 0.0))


def test_spec_fmu_state_restores_bit_for_bit(bench_fmu):
    """Catches a SpecPlant FMU state that does not continue a run bit for bit."""
    fmu = FmuInstance(bench_fmu, {"x0": START[0], "y0": START[1]})
    for i in range(5):
        fmu.step(1e-3, tau1=0.02, tau2=-0.01)
    state = fmu.fmu.getFMUstate()
    blob = fmu.fmu.serializeFMUstate(state)

    def run():
        for i in range(5):
            fmu.step(1e-3, tau1=0.02, tau2=-0.01)
        return fmu.get("x"), fmu.get("y"), fmu.get("dq1_elbow")

    first = run()
    fmu.fmu.setFMUstate(state)
    fmu.time = 5e-3
    assert run() == first
    fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(blob))
    fmu.time = 5e-3
    assert run() == first
    fmu.close()


def test_spec_fmu_refuses_substeps_it_cannot_take_in_time(bench_fmu):
    """Catches a SpecPlant FMU that accepts more sub-steps than one call may do."""
    fmu = FmuInstance(bench_fmu, {"substeps": 10000})
    error = fmu.refused_step()
    assert "substeps = 10000" in error and "allowed per call" in error
    fmu.close()
