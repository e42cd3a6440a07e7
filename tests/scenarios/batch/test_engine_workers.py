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


def test_a_scheduler_is_connected_to_and_the_cluster_options_reach_a_local_one(monkeypatch):
    """distributed's Client and LocalCluster replaced by recorders: a scheduler's address is
    the client's, no local cluster is made and the client is closed on leaving; without one, a
    LocalCluster of ``workers`` single-threaded workers (processes or threads as asked, the
    worker-path preload only for processes), closed on leaving.  Catches the address not used,
    a local cluster started beside a scheduler, the worker count or threads per worker wrong,
    and ``processes`` ignored."""
    import distributed

    log = []

    class _Recorder:
        def __init__(self, *args, **kwargs):
            log.append((type(self).__name__, args, kwargs))

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            log.append(("closed", type(self).__name__))

    class Client(_Recorder):
        pass

    class LocalCluster(_Recorder):
        pass

    monkeypatch.setattr(distributed, "Client", Client)
    monkeypatch.setattr(distributed, "LocalCluster", LocalCluster)
    with engine.open_client(scheduler="tcp://10.0.0.2:8786") as client:
        assert isinstance(client, Client)
    assert log == [("Client", ("tcp://10.0.0.2:8786",), {}), ("closed", "Client")]
    log.clear()
    with engine.open_client(workers=3, processes=False):
        pass
    (kind, args, options), (client_kind, (cluster,), _), *closed = log
    assert kind == "LocalCluster" and client_kind == "Client" and isinstance(cluster, LocalCluster)
    assert (options["n_workers"], options["threads_per_worker"], options["processes"], options["preload"]) == \
        (3, 1, False, [])
    assert sorted(closed) == [("closed", "Client"), ("closed", "LocalCluster")]
    log.clear()
    with engine.open_client(workers=2):
        pass
    assert log[0][2]["processes"] is True and log[0][2]["preload"] == [engine.worker_path.__file__]
