"""The batch engine's default worker count (:func:`scenarios.batch.engine.default_workers`)."""
from __future__ import annotations

import os

import pytest

from scenarios.batch import engine


@pytest.mark.parametrize("cores, workers", [(3, 3), (1, 1), (None, 1)])
def test_one_worker_per_core_and_one_when_the_count_is_unknown(monkeypatch, cores, workers):
    """``os.cpu_count()`` workers, 1 when Python cannot tell (None).  Catches always 1 worker
    (``and`` for ``or``) or no fallback."""
    monkeypatch.setattr(os, "cpu_count", lambda: cores)
    assert engine.default_workers() == workers
