"""Scenes as data: what a scene is (``scene``), the thesis' and seed 001's bench scenes (``thesis``),
the wheeled pendulum's (``pendulum``), the bench twin (``twin``, its fit ``bench_twin.toml``),
every scene by name (``catalogue``), a scene changed (``transforms``) or perturbed (``perturb``).

The names below are the ones ``scenarios.scenes`` held before the layout of issue 29
(README, docs/index.md); code inside the project imports them from their modules.
"""
from scenarios.scenes.catalogue import get_scene, scene_names  # noqa: F401
from scenarios.scenes.scene import SETTLE_TIME, STEADY_STATE_WINDOW, Scene  # noqa: F401
from scenarios.scenes.thesis import (DRIVE_TORQUE_OUTPUT, ELECTRICS, REFERENCE_SIGNALS,  # noqa: F401
                                     VERTICAL_COUNTER_MASSES, VERTICAL_GRAVITY, Fidelity, bench,
                                     thesis_sim_circle, vertical_circle)
from scenarios.scenes.transforms import (SAMPLE_TIME_MODELS, drive_joints, drives_in_plant,  # noqa: F401
                                         with_fmu_files, with_sample_time)
