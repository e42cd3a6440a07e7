"""plant/specsim.py: the settings a spec plant refuses, and the loop-closure tolerance its
assembly reaches (``ASSEMBLY_TOLERANCE``, 1e-14 m) even when Newton converges slowly."""
from __future__ import annotations

import numpy as np
import pytest

import plant.specsim as specsim
from plant import IntegratorSettings
from plant import spec as plant_spec
from plant.parallel import mechanism_state


@pytest.mark.parametrize("settings", [IntegratorSettings(kernel="fast", project=False),
                                      IntegratorSettings(kernel="general", project=True),
                                      IntegratorSettings(kernel="fast", project=True)],
                         ids=["fast", "projection", "both"])
def test_a_spec_plant_refuses_the_compiled_kernel_and_projection_each_alone(settings):
    """Either one is enough to refuse: the compiled kernel is the 5R's alone, and the spec
    plant has no projection."""
    spec = plant_spec.load("bench_5r")
    with pytest.raises(ValueError, match=rf"kernel = '{settings.kernel}', project = {settings.project}: "
                                         "a spec plant runs the general kernel without projection"):
        specsim.SpecSimulator(spec, (0.07, 0.17, 0.0), settings=settings)


def test_a_spec_plant_accepts_the_general_kernel_without_projection():
    sim = specsim.SpecSimulator(plant_spec.load("bench_5r"), (0.07, 0.17, 0.0),
                                settings=IntegratorSettings(kernel="general", project=False))
    assert sim.time == 0.0 and sim.y.size % 2 == 0


def test_assembly_closes_the_loop_to_1e_14_m_even_when_newton_only_halves_the_residual(monkeypatch):
    """A Newton that takes half of each step (the residual halves per iteration, so some
    iterate lands in every factor-of-2 window) must still go on to the documented 1e-14 m,
    not stop at the first residual a looser tolerance would take."""
    exact = specsim.left_inverse_solve
    monkeypatch.setattr(specsim, "left_inverse_solve", lambda A, b: 0.5 * exact(A, b))
    spec = plant_spec.load("bench_5r")
    q = specsim.assemble(spec, (0.07, 0.17, 0.0))
    assert q[:3] == pytest.approx([0.07, 0.17, 0.0], abs=1e-16)
    assert np.linalg.norm(mechanism_state(spec.mechanism, q, np.zeros_like(q)).residual) <= 1e-14
