"""Plant constants and defaults against the documents that state them, as literals: a test
that reads the constant itself follows a changed constant, this one does not."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

from plant import fivebar, get_preset
from plant.wheeled import WheeledPendulum

DOCS = Path(__file__).resolve().parents[2] / "docs"


def _doc(name):
    return " ".join((DOCS / name).read_text().split())


def test_the_near_singular_band_is_docs_plant_md_s_0_1():
    assert "below `NEAR_SINGULAR_MARGIN` = 0.1 as the near-singular band" in _doc("plant.md")
    assert fivebar.NEAR_SINGULAR_MARGIN == 0.1
    ws = fivebar.workspace_map(get_preset("bench"), step=0.01)
    inside = ~(ws.status == ws.OUTSIDE)
    near = ws.status[inside] == ws.NEAR_SINGULAR
    assert ((ws.margin[inside] < 0.1) == near).all() and near.any() and (~near).any()


def test_the_pendulum_s_defaults_are_docs_contract_md_s():
    """contract.md: substeps (RK4 per step, 2), encoder_counts (4096)."""
    assert "`substeps` (RK4 per step, 2), `encoder_counts` (4096)" in _doc("contract.md")
    sim = WheeledPendulum()
    assert sim.substeps == 2
    assert sim.count == pytest.approx(2.0 * math.pi / 4096, rel=1e-15)
    assert (sim.model, sim.time, sim.fallen) == ("exact", 0.0, False)
