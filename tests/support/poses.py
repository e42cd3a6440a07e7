"""Random end-effector poses of the 5R inside its workspace, away from singularities."""
from __future__ import annotations

from plant import fivebar


def random_poses(params, rng, n, band=fivebar.NEAR_SINGULAR_MARGIN, ys=(0.03, 0.29)):
    """n (x, y) with x in [-0.12, 0.12] m, y in ``ys`` and singularity margin >= band."""
    poses = []
    while len(poses) < n:
        x, y = rng.uniform(-0.12, 0.12), rng.uniform(*ys)
        try:
            if fivebar.singularity(params, x, y).margin >= band:
                poses.append((x, y))
        except fivebar.KinematicsError:
            pass
    return poses
