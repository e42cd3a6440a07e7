"""plant/specsim.py's assembly (continuation from the working-mode pose, Newton on the loop
closure) against the 5R's closed-form inverse kinematics (plant.fivebar.inverse_kinematics,
elbows outward), over the whole workspace: far start points the continuation must walk to
(a straight Newton jump from the working-mode pose fails or lands on another branch there)."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

from plant import fivebar, get_preset
from plant import spec as plant_spec
from plant.parallel import mechanism_state
from plant.specsim import ASSEMBLY_TOLERANCE, AssemblyError, SpecSimulator, assemble, reference_pose

#: Start points [m] across the workspace; (-0.2, -0.1) and (-0.2, 0.0) are beyond where one
#: Newton solve from the working-mode pose converges to the working mode.
STARTS = [(0.07, 0.17), (-0.2, 0.0), (-0.2, -0.1), (0.2, 0.05), (0.15, -0.05), (-0.05, 0.25)]


def wrapped(angle):
    return math.remainder(angle, 2 * math.pi)


@pytest.mark.parametrize("spec_name, preset", [("bench_5r", "bench"), ("thesis_sim_5r", "thesis_sim")])
def test_assembly_is_the_closed_form_working_mode_at_every_start(spec_name, preset):
    """Catches an assembly that jumps to the start point instead of walking to it (a wrong
    branch, or a refusal, far from the working-mode pose), walks a wrong path, stops short of
    the point, or closes the loop only loosely."""
    spec, params = plant_spec.load(spec_name), get_preset(preset)
    names = {info.name: k for k, _, info in spec.joints()}
    for x, y in STARTS:
        q = assemble(spec, (x, y, 0.0))
        phi11, phi12, phi21, phi22 = fivebar.inverse_kinematics(params, x, y)
        assert q[:3] == pytest.approx([x, y, 0.0], abs=1e-16)
        expected = {"q1": phi11, "q1_elbow": phi12 - phi11, "q2": phi21, "q2_elbow": phi22 - phi21}
        for name, angle in expected.items():
            assert abs(wrapped(q[names[name]] - angle)) < 1e-9, (spec_name, (x, y), name, q[names[name]], angle)
        assert np.linalg.norm(mechanism_state(spec.mechanism, q, np.zeros_like(q)).residual) <= ASSEMBLY_TOLERANCE


def test_the_working_mode_pose_puts_the_platform_at_the_chains_tips_mean():
    """Catches a reference pose that takes the joints' values from elsewhere than their
    ``mode`` or places the platform other than at the mean of the chains' tips."""
    spec = plant_spec.load("bench_5r")
    q = reference_pose(spec)
    for k, _, info in spec.joints():
        assert q[k] == info.mode
    params = get_preset("bench")
    tips = [(base + c.l1 * math.cos(a) + c.l2 * math.cos(a + b), c.l1 * math.sin(a) + c.l2 * math.sin(a + b))
            for base, c, a, b in ((params.l0, params.chain1, q[3], q[4]), (-params.l0, params.chain2, q[5], q[6]))]
    assert q[:2] == pytest.approx(np.mean(tips, axis=0), abs=1e-15) and q[2] == 0.0


@pytest.mark.parametrize("start", [(0.0, 0.4, 0.0), (math.nan, 0.1, 0.0), (0.1, math.inf, 0.0), (0.1, 0.1)])
def test_a_start_out_of_reach_or_not_three_finite_numbers_is_refused_naming_it(start):
    """Catches a simulator that starts from a pose whose loop cannot close, or accepts a start
    that is not 3 finite numbers, and a message that does not name the start."""
    spec = plant_spec.load("bench_5r")
    if len(start) == 3 and all(math.isfinite(v) for v in start):
        with pytest.raises(AssemblyError, match=r"^cannot close the loop with the platform at \[") as caught:
            SpecSimulator(spec, start)
        assert "out of reach, or a singularity between it and the working-mode pose" in str(caught.value)
    else:
        with pytest.raises(ValueError, match=re.escape(f"start = {tuple(start)!r} must be 3 finite numbers [m]")):
            SpecSimulator(spec, start)


def test_the_working_mode_pose_and_assembly_do_not_move_when_base_and_attach_shift_together():
    """Moving a chain's base and its attach point x_i by the same offset leaves its loop closure
    (5.12, d_i = o_i - x_i) and so the platform's pose unchanged: the tips move by the offset,
    tip - attach does not.  Catches a reference pose that places the platform at the chains'
    tips without subtracting their attach points (bench_5r's are all zero, and delta3's sum to
    zero: neither shows it)."""
    import dataclasses

    spec = plant_spec.load("bench_5r")
    offsets = [(0.125, -0.0625, 0.0), (-0.03125, 0.25, 0.0)]        # unequal, exact in binary
    shifted = dataclasses.replace(spec, chains=tuple(
        dataclasses.replace(c, base=tuple(np.add(c.base, o)), attach=tuple(np.add(c.attach, o)))
        for c, o in zip(spec.chains, offsets)))
    assert shifted.mechanism.d == pytest.approx(spec.mechanism.d, abs=1e-16)      # o_i - x_i: the same loop
    assert reference_pose(shifted) == pytest.approx(reference_pose(spec), abs=1e-15)
    assert assemble(shifted, (0.07, 0.17, 0.0)) == pytest.approx(assemble(spec, (0.07, 0.17, 0.0)), abs=1e-12)
