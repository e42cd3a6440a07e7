"""The Gauss-Seidel stepping order at the exhaustive search's limit itself (issue 31, session 44:
test_master_order_sizes.py tries EXHAUSTIVE_LIMIT - 7 and + 1, never the limit).

docs/master.md: the order is searched exhaustively "for up to 16 components in a loop"; beyond,
the listing order is kept where the samples allow.  A loop whose order is forced by sampled
connections (c2 -> c3 -> ... : few placed sets, so the search at 16 components is fast) but for c0
and c1, where c1 reads c0's continuous output: the search puts c1 first (no connection read at
t + h), the listing order keeps c0 first (one read late).
"""
from __future__ import annotations

import pytest

from fmus.cosim import master
from tests.fmus.cosim.test_master_order_sizes import _system
from tests.support.paths import ROOT

DOCUMENTED_LIMIT = 16


def _order(n: int) -> tuple:
    chain = [(k, k + 1) for k in range(2, n - 1)]          # c(k+1) reads c(k)'s sampled output
    system, variables = _system(n, chain, soft=[(0, 1)])   # c1 reads c0's continuous output
    return master.stepping_order(system, variables)


@pytest.mark.parametrize("n, first", [(DOCUMENTED_LIMIT, ("c1", "c0")), (DOCUMENTED_LIMIT + 1, ("c0", "c1"))])
def test_sixteen_components_are_searched_and_seventeen_keep_the_listing_order(n, first):
    """Catches the limit met on the wrong side (``>`` -> ``>=``: 16 components not searched) or moved."""
    doc = " ".join((ROOT / "docs" / "master.md").read_text(encoding="utf-8").split())
    assert f"exhaustive search for up to {DOCUMENTED_LIMIT} components" in doc
    order = _order(n)
    assert order == (*first, *(f"c{k}" for k in range(2, n)))
