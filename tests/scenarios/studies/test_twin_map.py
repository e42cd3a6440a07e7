"""scenarios/studies/twin_fit.py's ``_map``, the fit's fan-out: with more than one worker the
calls go to a dask client (``scenarios.batch.engine.open_client``, replaced here by a made-up
client that checks its arguments as dask's ``Client.map`` reads them) and give what the serial
path gives, item by item in order (issue 31: an option, ``workers``, taking effect; the
parallel path was run by no test)."""
from __future__ import annotations

import pytest

from scenarios.batch import engine
from scenarios.studies import twin_fit


class _Client:
    """dask's map(func, *iterables, pure=...) -> futures, gather(futures) -> results."""

    def __init__(self, log):
        self.log = log

    def map(self, function, *iterables, pure=True):
        assert callable(function), f"map's first argument {function!r} is not the function"
        assert len({len(i) for i in iterables}) == 1, "map's iterables differ in length"
        self.log.append(("map", function, [list(i) for i in iterables], pure))
        return [("future", function(*arguments)) for arguments in zip(*iterables)]

    def gather(self, futures):
        return [value for tag, value in futures if tag == "future"]


@pytest.fixture
def client(monkeypatch):
    log = []

    class _Open:
        def __init__(self, scheduler=None, workers=None, processes=True):
            log.append(("open", scheduler, workers, processes))

        def __enter__(self):
            return _Client(log)

        def __exit__(self, *exc):
            log.append(("close",))

    monkeypatch.setattr(engine, "open_client", _Open)
    return log


def _one(item, extra):
    return (item, extra)


def _star(item, first, second):
    return item * first - second


def test_one_worker_calls_in_this_process_and_more_go_to_the_cluster_with_the_same_results(client):
    """Catches the extra argument not given to every item (or given as a list of the wrong
    length), the function and the items swapped, the cluster not of ``workers`` or not closed,
    results out of the items' order, and the parallel path taken for one worker."""
    items, extra = [3, 1, 2], {"seeds": (101, 102)}
    serial = twin_fit._map(_one, items, extra, workers=1)
    assert serial == [(3, extra), (1, extra), (2, extra)] and client == []
    assert twin_fit._map(_one, items, extra, workers=3) == serial
    assert client == [("open", None, 3, True), ("map", _one, [items, [extra] * 3], False), ("close",)]


def test_star_spreads_a_tuple_of_extra_arguments_in_both_paths(client):
    """Catches ``star`` passing the tuple as one argument, or its entries in another order."""
    serial = twin_fit._map(_star, [2, 5], (10, 1), workers=1, star=True)
    assert serial == [19, 49]
    assert twin_fit._map(_star, [2, 5], (10, 1), workers=2, star=True) == serial
    assert client[1] == ("map", _star, [[2, 5], [10, 10], [1, 1]], False)
