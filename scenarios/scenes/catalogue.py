"""Every scene by name: the thesis' and seed 001's (:mod:`scenarios.scenes.thesis`), the bench twin's
(:mod:`scenarios.scenes.twin`) and the wheeled pendulum's (:mod:`scenarios.scenes.pendulum`)."""
from __future__ import annotations

from controller.strategies import ALL_STRATEGY_NAMES
from scenarios.scenes.pendulum import PENDULUM_SCENES, pendulum_scene
from scenarios.scenes.scene import Scene
from scenarios.scenes.thesis import bench, thesis_sim_circle, vertical_circle
from scenarios.scenes.twin import bench_real, twin_scene_names, twin_scenes


def scene_names() -> list[str]:
    """Every scene name ``get_scene`` accepts."""
    names = ["thesis_sim_circle", "thesis_sim_circle_me20", "thesis_sim_circle_me40"]
    names += [f"bench_{kind}_{s}" for kind in ("circle", "triangle") for s in ALL_STRATEGY_NAMES]
    names += [f"vertical_circle_{b}{s}" for b in ("", "balanced_") for s in ALL_STRATEGY_NAMES]
    names += twin_scene_names()
    return names + list(PENDULUM_SCENES)


def get_scene(name: str) -> Scene:
    """The scene called ``name`` (see :func:`scene_names`)."""
    if name == "thesis_sim_circle":
        return thesis_sim_circle()
    for error in (20, 40):
        if name == f"thesis_sim_circle_me{error}":
            return thesis_sim_circle(model_error=error / 100)
    for kind in ("circle", "triangle"):
        prefix = f"bench_{kind}_"
        if name.startswith(prefix) and name[len(prefix):] in ALL_STRATEGY_NAMES:
            return bench(name[len(prefix):], kind)
    if name in twin_scenes():
        kind, strategy = twin_scenes()[name]
        return bench_real(strategy, kind)
    for balanced in (True, False):
        prefix = "vertical_circle_balanced_" if balanced else "vertical_circle_"
        if name.startswith(prefix) and name[len(prefix):] in ALL_STRATEGY_NAMES:
            return vertical_circle(name[len(prefix):], balanced)
    if name in PENDULUM_SCENES:
        return pendulum_scene(name)
    raise ValueError(f"unknown scene {name!r}; `parcosim list` prints the {len(scene_names())} scenes")
