"""The balanced 5R of seed 001 (55)-(72): counter-masses placed by (64) on each chain.

The oracle is the independent Lagrange model of ``tests/support/lagrange5r.py``, where
each counter-mass is a particle of its own (no composite link); the placement is derived
here from that model's potential energy, not taken from the plant.
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from plant import ACCURATE, IntegratorSettings, PlantSimulator, get_preset
from plant import fivebar
from plant.serial import chain_dynamics
from tests.support import lagrange5r as ref
from tests.plant.test_plant_dynamics import reference_params

pytestmark = [pytest.mark.slow]

GRAVITY = (1.3, -9.81, 0.5)      # in-plane x and y parts, and a z part that must not matter
COUNTER = (0.4, 0.2)             # kg on the proximal and on the distal links


def balanced(preset="bench", gravity=GRAVITY, counter=COUNTER):
    return replace(get_preset(preset), gravity=gravity).with_counter_masses(*counter)


def balancing_offsets(chain, M1, M2):
    """Where point masses M1 (link 1, from the base) and M2 (link 2, from the elbow) zero the
    chain's weight moments: the distal link's mass centre at the elbow, then the proximal
    link's (carrying m2 + M2 at the elbow) at the base joint."""
    L2 = -chain["m2"] * chain["lg2"] / M2
    L1 = -(chain["m1"] * chain["lg1"] + (chain["m2"] + M2) * chain["l1"]) / M1
    return L1, L2


def reference_balanced(params, counter=COUNTER):
    rp = reference_params(params)
    for chain in rp["chains"]:
        L1, L2 = balancing_offsets(chain, *counter)
        chain.update(M1=counter[0], L1=L1, M2=counter[1], L2=L2)
    return rp


def test_the_placement_makes_the_independent_model_weightless():
    """With the particles where the test puts them, the Lagrange model's potential energy is
    the same at random poses and its gravity forces vanish; the plant puts them there."""
    params = balanced()
    rp = reference_balanced(params)
    rng = np.random.default_rng(11)
    energies = []
    for _ in range(20):
        phi = rng.uniform(-math.pi, math.pi, 4)
        np.testing.assert_allclose(ref.gravity_forces(rp, phi), 0.0, atol=1e-15)
        energies.append(ref.potential_energy(rp, phi))
    assert np.ptp(energies) < 1e-15
    unbalanced = reference_params(params)
    assert np.ptp([ref.potential_energy(unbalanced, rng.uniform(-3, 3, 4)) for _ in range(5)]) > 1e-3
    for c, rc in zip((params.chain1, params.chain2), rp["chains"]):
        np.testing.assert_allclose(c.counter_offsets(), (rc["L1"], rc["L2"]), rtol=1e-15)


@pytest.mark.parametrize("preset", ["thesis_sim", "bench"])
def test_each_chain_is_the_balanced_rr_of_seed_001(preset):
    """Seed 001 (65)-(71), typos corrected: g# = 0, v# = 0 and a constant M# with
    M11 = Jz1 + Jz2 + m1 lg1^2 + m2 lg2^2 + l1^2 (M2 + m2) + m2^2 lg2^2 / M2
          + (m1 lg1 + (M2 + m2) l1)^2 / M1 (+ the rotor), M12 = M22 = Jz2 + m2 (M2 + m2) lg2^2 / M2."""
    params = balanced(preset)
    M1, M2 = COUNTER
    rng = np.random.default_rng(12)
    for c in (params.chain1, params.chain2):
        chain = fivebar._rr_chain(c)
        m11 = (c.Jz1 + c.Jz2 + c.m1 * c.lg1 ** 2 + c.m2 * c.lg2 ** 2 + c.l1 ** 2 * (M2 + c.m2)
               + c.m2 ** 2 * c.lg2 ** 2 / M2 + (c.m1 * c.lg1 + (M2 + c.m2) * c.l1) ** 2 / M1 + c.J_rotor)
        m22 = c.Jz2 + c.m2 * (M2 + c.m2) * c.lg2 ** 2 / M2
        for _ in range(10):
            q, dq = rng.uniform(-math.pi, math.pi, 2), rng.uniform(-5, 5, 2)
            d = chain_dynamics(chain, q, dq, np.array(GRAVITY))
            np.testing.assert_allclose(d.g, 0.0, atol=1e-15)
            np.testing.assert_allclose(d.v, 0.0, atol=1e-15)
            np.testing.assert_allclose(d.M, [[m11, m22], [m22, m22]], rtol=1e-13)


def torque_profile(t):
    return 0.15 * math.sin(2 * math.pi * 2.5 * t) + 0.05, -0.12 * math.cos(2 * math.pi * 1.5 * t)


@pytest.mark.parametrize("kernel, steps", [("fast", 300), ("general", 100)])
def test_path_under_gravity_and_torques_equals_the_point_mass_model(kernel, steps):
    """0.3 s (general kernel: 0.1 s) of torques under in-plane gravity: end effector within 1e-9 m of the Lagrange
    model with the counter-masses as particles (each torque held over its 1 ms step)."""
    params = balanced()
    rp = reference_balanced(params)
    x0, y0 = 0.0, 0.15
    sim = PlantSimulator(params, x0, y0, replace(ACCURATE, kernel=kernel))
    phi = ref.ik(rp, x0, y0)
    q, dq = np.array([phi[0], phi[2]]), np.zeros(2)
    worst = 0.0
    for k in range(steps):
        held = torque_profile(k * 1e-3)
        _, qs, dqs = ref.integrate(rp, q, dq, lambda t: held, 1e-3)
        q, dq = qs[-1], dqs[-1]
        sim.step(*held, 1e-3)
        x, y = ref.tip(rp, ref.full_state(rp, q, dq)[0])
        out = sim.outputs()
        worst = max(worst, math.hypot(out["x"] - x, out["y"] - y))
    assert math.hypot(x - x0, y - y0) > 0.001          # it moved
    assert worst < 1e-9


@pytest.mark.parametrize("kernel, seconds", [("fast", 10.0), ("general", 0.2)])
def test_released_at_rest_it_stays(kernel, seconds):
    """Zero torque under in-plane gravity: the balanced 5R moves <= 1e-12 m (the unbalanced
    one falls by millimetres in 0.1 s)."""
    settings = IntegratorSettings(kernel=kernel)
    sim = PlantSimulator(balanced(), 0.03, 0.16, settings)
    start = np.array([sim.outputs()["x"], sim.outputs()["y"]])
    worst = 0.0
    for _ in range(round(seconds / 1e-3)):
        sim.step(0.0, 0.0, 1e-3)
        worst = max(worst, float(np.hypot(*(np.array([sim.outputs()["x"], sim.outputs()["y"]]) - start))))
    assert worst <= 1e-12
    falling = PlantSimulator(replace(balanced(), chain1=get_preset("bench").chain1, chain2=get_preset("bench").chain2),
                             0.03, 0.16, settings)
    for _ in range(100):
        falling.step(0.0, 0.0, 1e-3)
    assert math.hypot(falling.outputs()["x"] - 0.03, falling.outputs()["y"] - 0.16) > 1e-3


def test_counter_masses_with_an_end_effector_mass_or_too_light_are_refused():
    """Catches counter masses accepted with an end-effector mass (the balance then fails silently), a near-
    zero counter mass (ill-conditioned), or a negative one."""
    with pytest.raises(ValueError, match=r"m0 = 0\.02 kg with counter-masses.*set m0 = 0"):
        PlantSimulator(replace(balanced(), m0=0.02), 0.0, 0.15)
    with pytest.raises(ValueError, match=r"chain1\.counter_mass2 = 1e-06 kg is too light"):
        PlantSimulator(balanced(counter=(0.4, 1e-6)), 0.0, 0.15)
    with pytest.raises(ValueError, match=r"chain1\.counter_mass1 must be >= 0, got -0\.1"):
        PlantSimulator(balanced(counter=(-0.1, 0.2)), 0.0, 0.15)


def test_zero_counter_masses_leave_the_fast_kernel_bit_identical():
    """Catches zero counter masses changing the fast kernel's parameters (the unbalanced bench's results
    would move)."""
    from plant.fast5r import pack_params

    bench = get_preset("bench")
    assert pack_params(bench.with_counter_masses(0.0, 0.0)).tobytes() == pack_params(bench).tobytes()


def test_fmus_take_the_counter_masses(built_fmus):
    """FiveBarPlant and ActuatedFiveBarPlant with counter_mass1/2 under gravity: the same
    plant as in-process (bit for bit), at rest without torque; m0 with them is refused."""
    from tests.support.fmi_support import FmuInstance

    parameters = {"preset": "bench", "x0": 0.03, "y0": 0.16, "gravity_x": GRAVITY[0], "gravity_y": GRAVITY[1],
                  "gravity_z": GRAVITY[2], "counter_mass1": COUNTER[0], "counter_mass2": COUNTER[1]}
    fmu = FmuInstance(built_fmus["FiveBarPlant"], parameters)
    sim = PlantSimulator(balanced(), 0.03, 0.16)
    for k in range(200):
        tau = (0.0, 0.0) if k < 100 else torque_profile(k * 1e-3)
        fmu.step(1e-3, tau1=tau[0], tau2=tau[1])
        sim.step(*tau, 1e-3)
        if k == 99:
            assert math.hypot(fmu.get("x") - 0.03, fmu.get("y") - 0.16) <= 1e-12
    assert (fmu.get("x"), fmu.get("y")) == (sim.outputs()["x"], sim.outputs()["y"])
    fmu.close()
    for model in ("FiveBarPlant", "ActuatedFiveBarPlant"):
        refused = FmuInstance(built_fmus[model], {**parameters, "m0": 0.02})
        assert "m0 = 0.02 kg with counter-masses" in refused.refused_step(1e-3)
        refused.close()
        negative = FmuInstance(built_fmus[model], {**parameters, "counter_mass2": -0.2})
        assert "counter_mass2 = -0.2 kg must be >= 0" in negative.refused_step(1e-3)
        negative.close()
