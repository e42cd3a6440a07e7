"""``parcosim run --drives-in-plant N`` at the edge of its range (parcosim/cli.py ``_scene``;
issue 31, training sweep s44: compare mutant at cli.py:399).

N is the RK4 steps per sample of the drives moved into the plant: at least 1.  N = 1 is a scene
with the drives inside the plant at one step per sample; N = 0 is refused by the scene's own
check (also when the option's parser is bypassed), naming the option and the bound.
"""
from __future__ import annotations

from argparse import Namespace

import pytest

from parcosim import cli
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant

SCENE = "bench_circle_TCMDx"


def test_one_rk4_step_per_sample_is_the_scene_with_its_drives_in_the_plant_at_one_step():
    """N = 1, the least: the scene is drives_in_plant(scene, substeps=1), built here."""
    got = cli._scene(Namespace(scene=SCENE, drives_in_plant=1, replace=[]))
    assert got == drives_in_plant(get_scene(SCENE), substeps=1)
    assert got != get_scene(SCENE)


def test_zero_rk4_steps_per_sample_is_refused_naming_the_option_and_the_bound():
    """N = 0 refused with the option, its value and ">= 1"."""
    with pytest.raises(ValueError, match=r"^--drives-in-plant 0: the RK4 steps per sample must be >= 1$"):
        cli._scene(Namespace(scene=SCENE, drives_in_plant=0, replace=[]))
