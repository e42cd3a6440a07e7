"""``controller.model.workspace_extent``: a box holding every point of the upper half-plane
both chains reach (checked here on a grid of points, reach computed from the link lengths),
and no larger than the chains' reach about their bases."""
import numpy as np

from controller.model import workspace_extent
from plant import get_preset


def test_the_workspace_extent_holds_every_point_both_chains_reach():
    for name in ("bench", "thesis_sim"):
        p = get_preset(name)
        x0, x1, y0, y1 = workspace_extent(p)
        bases = ((p.l0, 0.0, p.chain1), (-p.l0, 0.0, p.chain2))
        # every point in reach of both chains (|l1 - l2| <= distance <= l1 + l2), y >= 0
        xs, ys = np.meshgrid(np.linspace(-1.0, 1.0, 801), np.linspace(0.0, 1.0, 401))
        reached = np.ones_like(xs, dtype=bool)
        for bx, by, c in bases:
            d = np.hypot(xs - bx, ys - by)
            reached &= (d <= c.l1 + c.l2) & (d >= abs(c.l1 - c.l2))
        assert reached.sum() > 1000
        px, py = xs[reached], ys[reached]
        assert x0 <= px.min() and px.max() <= x1 and y0 <= py.min() and py.max() <= y1, name
        # no larger than the chains' reach about their bases (and y from 0)
        reach = max(c.l1 + c.l2 for _, _, c in bases)
        assert (x0, x1, y0, y1) == (-p.l0 - reach, p.l0 + reach, 0.0, reach)
