"""The in-process step's short cuts (docs/benchmarks.md, "The slaves' Python layers"): each
gives what the general path it bypasses gives."""
from __future__ import annotations

import math

import numpy as np
import pytest

from controller.derivators import Derivator
from fmus.slave.declarations import PLANT_OUTPUTS
from fmus.slaves.parcosim_derivator import Derivator as DerivatorSlave
from plant import PlantSimulator, get_preset


def test_plant_output_values_are_outputs_in_the_declared_order():
    """Catches the fast output path (the C kernel's report) giving other values, another order or numpy
    scalars than outputs(), or a stale report after the state is set from outside."""
    sim = PlantSimulator(get_preset("bench"), -0.002, 0.108)
    names = [name for name, _ in PLANT_OUTPUTS]
    assert list(sim.outputs()) == names
    assert sim.output_values() == list(sim.outputs().values())   # before any step: the general path
    for k in range(20):
        sim.step(0.02 * math.sin(k), -0.01, 1e-3)
        assert sim._last[2] is not None                          # the C kernel's step left its report
        values = sim.output_values()                             # after a kernel step: the report's
        assert values == list(sim.outputs().values())
        assert all(type(v) is float for v in values)
    sim.y = sim.y.copy()                                         # a state set from outside: recomputed
    assert sim.output_values() == list(sim.outputs().values())


def _slave(**parameters):
    slave = DerivatorSlave(instance_name="d")
    for name, value in parameters.items():
        setattr(slave, name, value)
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    return slave


class _Fixed:
    """A derivator whose estimates are given."""

    def __init__(self, estimates):
        self.estimates = estimates

    def step_values(self, q, limit):
        return list(self.estimates)


def test_derivator_accepts_finite_estimates_whose_sum_overflows():
    """Catches a finiteness check written on a sum of the estimates (which overflows to inf for finite
    values) refusing a good step."""
    slave = _slave()
    slave.derivator = _Fixed((1e308, 1e308, -0.5, 2.0))
    assert slave.do_step(0.0, 1e-3)
    assert (slave.dq1, slave.dq2, slave.ddq1, slave.ddq2) == (1e308, 1e308, -0.5, 2.0)


@pytest.mark.parametrize("estimates", [(math.nan, 0.0, 0.0, 0.0), (0.0, 0.0, math.inf, 0.0),
                                       (math.inf, -math.inf, 0.0, 0.0), (1e308, 1e308, math.nan, 0.0)])
def test_derivator_refuses_estimates_that_are_not_finite(estimates):
    """Catches a NaN or infinite derivative estimate published, or a refusal that overwrites the last good
    estimates."""
    slave = _slave()
    slave.derivator = _Fixed(estimates)
    assert not slave.do_step(0.0, 1e-3)
    assert f"the estimates (dq1, dq2, ddq1, ddq2) = {tuple(estimates)!r} at t = 0 s are not finite" in slave.error
    assert (slave.dq1, slave.dq2, slave.ddq1, slave.ddq2) == (0.0, 0.0, 0.0, 0.0)   # the last good ones


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf], ids=["nan", "inf", "-inf"])
@pytest.mark.parametrize("position", range(4), ids=["dq1", "dq2", "ddq1", "ddq2"])
def test_derivator_refuses_any_one_estimate_that_is_not_finite_the_others_being(position, bad):
    """Each of the four outputs alone NaN or infinite (the other three finite) is refused and
    nothing is published. Catches the quick check of the sum leaving out one estimate: the sum
    of the other three is finite then, and the bad estimate would be published."""
    estimates = [0.25, -1.5, 3.0, -4.0]
    estimates[position] = bad
    slave = _slave()
    slave.derivator = _Fixed(estimates)
    assert not slave.do_step(0.0, 1e-3)
    assert f"the estimates (dq1, dq2, ddq1, ddq2) = {tuple(estimates)!r} at t = 0 s are not finite" in slave.error
    assert (slave.dq1, slave.dq2, slave.ddq1, slave.ddq2) == (0.0, 0.0, 0.0, 0.0)


def test_derivator_angles_in_any_form_numpy_takes_give_the_same_estimates():
    """Catches the derivator's fast path giving other estimates for angles given as strings, float32 or
    arrays, or accepting three angles."""
    floats, others = Derivator(60.0, 30.0, 1e-3), Derivator(60.0, 30.0, 1e-3)
    floats.reset([0.1, 0.2])
    others.reset([0.1, 0.2])
    for k in range(50):
        q = (0.1 + 1e-3 * k, 0.2 - 2e-3 * k)
        given = (str(q[0]), np.float32(q[1])) if k % 2 else np.array(q)   # numpy converts these
        expected = floats.step_values((q[0], float(np.float32(q[1]))) if k % 2 else q)
        assert others.step_values(given) == expected
    with pytest.raises(ValueError):
        others.step_values((0.1, 0.2, 0.3))
