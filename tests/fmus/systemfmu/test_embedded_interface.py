"""What a ControlChain exchanges with its plant (``fmus.systemfmu.cores.chain_interface``),
against docs/contract.md ("ControlChain": bench: ``q1_enc``, ``q2_enc``, ``dq1``, ``dq2``;
thesis_sim: ``q1``, ``q2``, ``dq1``, ``dq2``; the commands ``tau1``, ``tau2``, with
``--drives-in-plant`` ``v_ref1``, ``v_ref2``) and docs/ssp.md (with the drives in the plant
"the chain measures no speed"); the commands' sources are the scene's own connections into
the plant (issue 31: only a slow test held it)."""
from __future__ import annotations

import pytest

from fmus.cosim.system import split_signal
from fmus.systemfmu.cores import chain_interface
from scenarios.packaging.chain import package_scene
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant

DOCUMENTED = {"bench_circle_TCMDx": {"q1_enc", "q2_enc", "dq1", "dq2"}, "thesis_sim_circle": {"q1", "q2", "dq1", "dq2"},
              "drives_in_plant": {"q1_enc", "q2_enc"}}


@pytest.mark.parametrize("scene", sorted(DOCUMENTED))
def test_the_chain_measures_the_documented_signals_and_commands_what_the_scene_connects_in(scene):
    """Catches an output of another component (or of the plant, not measurable) taken as
    measured, a measurement left out or twice, and a command taken from the wrong signal."""
    chosen = drives_in_plant(get_scene("bench_circle_TCMDx"), substeps=2) if scene == "drives_in_plant" \
        else get_scene(scene)
    measured, commanded = chain_interface(package_scene(chosen).chain)
    assert set(measured) == DOCUMENTED[scene] and len(measured) == len(DOCUMENTED[scene])
    if scene == "drives_in_plant":
        assert commanded == {"v_ref1": "plant.v1", "v_ref2": "plant.v2"}
    else:
        into_plant = {split_signal(c.target)[1]: c.source for c in chosen.system.connections
                      if split_signal(c.target)[0] == "plant" and split_signal(c.source)[0] != "plant"}
        assert commanded == into_plant and set(commanded) == {"tau1", "tau2"}
