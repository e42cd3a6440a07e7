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


@pytest.mark.parametrize("workers", [0, -2, 1.5, "2"])
def test_a_cluster_of_a_bad_worker_count_is_refused_naming_it(workers):
    """open_client refuses a worker count that is not an integer >= 1 before starting anything,
    and workers together with a scheduler (that cluster has its own).  Catches a bound off by one
    (0 workers accepted) or the check skipped."""
    with pytest.raises(ValueError) as refusal:
        with engine.open_client(workers=workers):
            pass
    assert str(refusal.value) == f"workers = {workers!r} must be an integer >= 1"
    with pytest.raises(ValueError) as refusal:
        with engine.open_client("tcp://127.0.0.1:1", workers=2):
            pass
    assert str(refusal.value) == "workers = 2: the cluster at tcp://127.0.0.1:1 has its own workers"
