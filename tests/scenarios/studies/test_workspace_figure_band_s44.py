"""The workspace figure's trajectory check at the near-singular band's edge (issue 31, session 44:
boundaries of the generalised training sample): as the controller (controller/model.py: points
with margin < the band are left out), a sample whose margin equals the band exactly is kept,
one with a smaller margin is refused for the band."""
from __future__ import annotations

from plant import fivebar, get_preset
from scenarios.studies.workspace import figure


def test_a_sample_whose_margin_is_exactly_the_band_is_not_refused():
    """Catches ``<=`` for ``<`` on the margin."""
    params = get_preset("thesis_sim")
    pts = [(0.01, 0.16), (0.02, 0.15)]
    margins = [fivebar.singularity(params, x, y).margin for x, y in pts]
    band = margins[0]
    assert margins[1] < band
    extent = (-1.0, 1.0, -1.0, 1.0)
    check = figure.check_trajectory(params, "edge", lambda t: pts[round(t / 1e-3)], 1e-3, band=band, extent=extent)
    assert {r: i.tolist() for r, i in check.refused.items()} == {figure.OUTSIDE: [], figure.BAND: [1], figure.TABLE: []}
    assert check.min_margin == margins[1]
