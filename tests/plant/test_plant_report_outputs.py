"""A FiveBarPlant's outputs after a step of the C kernel come from the kernel's report
(plant/simulator.py, ``outputs`` / ``output_values``); they must be the outputs computed from the
state itself (the Python path: world angles and rates, tip, encoders, residual), each under
its own name, in a motion where every one of them differs."""
from __future__ import annotations

import math

import pytest

from plant import PlantSimulator, get_preset


def test_after_a_kernel_step_each_output_is_the_one_computed_from_the_state():
    """Catches a report word read into another output (q1/q2, rates, tip, its velocity,
    encoders swapped or shifted): after 1 ms steps of a moving bench plant, each output equals
    the quantity computed in Python from ``sim.y`` (the path without a report), to 1e-12 (the kernel rounds differently)."""
    sim = PlantSimulator(get_preset("bench"), 0.0, 0.15, dx0=0.4, dy0=-0.3)
    for k in range(5):
        sim.step(0.02, -0.01, 1e-3)
    assert sim._last is not None and sim._last[2] is not None      # the report's path is the one read
    out = sim.outputs()
    sim._last = None                  # the same outputs computed in Python from sim.y, not read from the report
    expected = sim.outputs()
    assert list(out) == list(expected)
    for name, value in expected.items():
        assert out[name] == pytest.approx(value, rel=1e-12, abs=1e-12), name
    # every output distinct here, so that one read in place of another is seen
    values = [v for k, v in expected.items() if k != "residual"]
    assert all(not math.isclose(a, b, abs_tol=1e-9) for i, a in enumerate(values) for b in values[i + 1:])
    assert sim.output_values() == list(out.values())


def test_the_pose_measures_from_the_kernel_report_are_the_python_ones_in_order():
    """``_measures_of`` (the kernel's report, so that a projected state is judged with a step's
    bits) gives sin theta12, sin theta22, sin(phi12 - phi22) as ``_pose_measures`` computes them
    from the angles, all three, in that order: a pose where the three differ."""
    sim = PlantSimulator(get_preset("bench"), 0.02, 0.17)
    expected = list(sim._pose_measures(sim.y))
    assert len({round(v, 6) for v in expected}) == 3
    assert sim._measures_of(sim.y) == pytest.approx(expected, rel=1e-13, abs=1e-15)
