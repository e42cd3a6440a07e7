"""The Gauss-Seidel stepping order (fmus/cosim/master.py ``stepping_order``) on either side of
EXHAUSTIVE_LIMIT: the exhaustive search up to it, the listing order's greedy pass beyond it.

With hard dependencies only (sampled outputs), every order costs nothing, so both must give
the earliest topological order by listing position: the component listed first among those
whose sources have all stepped, each time.  That order is computed here independently
(Kahn's algorithm with a heap of listing positions) for random dependency graphs of both
sizes; with soft (continuous) connections the exhaustive search must not do worse than any
topological order tried here.
"""
from __future__ import annotations

import heapq
import itertools
import random

import pytest

from fmus.cosim import master
from fmus.cosim.backends import Variable
from fmus.cosim.system import Component, Connection, System


def _system(n: int, edges: list, soft: list = ()) -> tuple:
    """``n`` components c0..c{n-1} in listing order; ``edges`` (a, b): b reads a's sampled output,
    ``soft`` (a, b): b reads a's continuous one.  Returns the system and its variables."""
    names = [f"c{i}" for i in range(n)]
    connections = [Connection(f"c{a}.d{b}", f"c{b}.in_d{a}") for a, b in edges]
    connections += [Connection(f"c{a}.s{b}", f"c{b}.in_s{a}") for a, b in soft]
    variables = {name: {} for name in names}
    for a, b in edges:
        variables[f"c{a}"][f"d{b}"] = Variable(f"d{b}", 0, "Real", "output", "discrete")
    for a, b in soft:
        variables[f"c{a}"][f"s{b}"] = Variable(f"s{b}", 0, "Real", "output", "continuous")
    system = System(tuple(Component(name, "Trajectory") for name in names), tuple(connections), (), 0.0)
    return system, variables


def _earliest_topological(n: int, edges: list) -> tuple:
    before = {b: set() for b in range(n)}
    for a, b in edges:
        before[b].add(a)
    ready = [i for i in range(n) if not before[i]]
    heapq.heapify(ready)
    order = []
    while ready:
        i = heapq.heappop(ready)
        order.append(i)
        for b in range(n):
            if i in before[b]:
                before[b].discard(i)
                if not before[b]:
                    heapq.heappush(ready, b)
    assert len(order) == n
    return tuple(f"c{i}" for i in order)


def _random_dag(rng: random.Random, n: int, density: float) -> list:
    """Edges of a random DAG over a random hidden order (so that many run against the listing)."""
    hidden = list(range(n))
    rng.shuffle(hidden)
    return [(hidden[i], hidden[j]) for i in range(n) for j in range(i + 1, n) if rng.random() < density]


@pytest.mark.parametrize("n", [master.EXHAUSTIVE_LIMIT - 7, master.EXHAUSTIVE_LIMIT + 1, master.EXHAUSTIVE_LIMIT + 9])
@pytest.mark.parametrize("seed", range(4))
def test_hard_dependencies_give_the_earliest_order_by_listing_at_any_size(n, seed):
    """Catches the greedy pass beyond the limit (and the search below it) placing a
    component before one it reads, skipping the first ready component, or failing on
    components that read nothing (an empty set of sources)."""
    rng = random.Random(1000 * n + seed)
    edges = _random_dag(rng, n, 0.15)
    system, variables = _system(n, edges)
    order = master.stepping_order(system, variables)
    assert order == _earliest_topological(n, edges)


def test_no_connections_keep_the_listing_order_beyond_the_limit():
    n = master.EXHAUSTIVE_LIMIT + 3
    system, variables = _system(n, [])
    assert master.stepping_order(system, variables) == tuple(f"c{i}" for i in range(n))


def _violations(order, soft) -> int:
    """Soft connections whose reader steps after its source (it reads t + h)."""
    position = {name: k for k, name in enumerate(order)}
    return sum(position[f"c{b}"] > position[f"c{a}"] for a, b in soft)


@pytest.mark.parametrize("seed", range(5))
def test_the_exhaustive_order_is_the_cheapest_with_soft_connections(seed):
    """Below the limit: no valid order tried here (topological orders, shuffled ties) has fewer
    soft connections read late, and ties go to the earliest listing.  Catches the search
    keeping a worse candidate for a placed set, or a better one not kept."""
    rng = random.Random(seed)
    n = 7
    edges = _random_dag(rng, n, 0.2)
    soft = [(a, b) for a in range(n) for b in range(n) if a != b and (a, b) not in edges and (b, a) not in edges
            and rng.random() < 0.25]
    system, variables = _system(n, edges, soft)
    order = master.stepping_order(system, variables)
    assert all(order.index(f"c{a}") < order.index(f"c{b}") for a, b in edges)
    best = _violations(order, soft)
    for perm in itertools.permutations(range(n)):
        position = {i: k for k, i in enumerate(perm)}
        if all(position[a] < position[b] for a, b in edges):
            candidate = tuple(f"c{i}" for i in perm)
            assert _violations(candidate, soft) >= best, (candidate, order)
            if _violations(candidate, soft) == best:
                assert perm >= tuple(int(name[1:]) for name in order)


@pytest.mark.parametrize("seed", range(4))
def test_the_exhaustive_order_counts_every_connection_of_a_pair(seed):
    """Several continuous connections between one pair of components: each one read late counts
    (docs: "the fewest connections read ... advanced to t + h"), so a pair joined three times
    weighs three single ones.  Held against every valid order, counted connection by connection.
    Catches a pair's count that starts at 1 (or counts each pair once), which weighs a
    crowded pair like a single connection and picks another order."""
    rng = random.Random(100 + seed)
    n = 6
    edges = _random_dag(rng, n, 0.15)
    pairs = [(a, b) for a in range(n) for b in range(n) if a != b and (a, b) not in edges and (b, a) not in edges
             and rng.random() < 0.3]
    soft = [(a, b, k) for a, b in pairs for k in range(rng.choice((1, 1, 2, 3)))]
    names = [f"c{i}" for i in range(n)]
    connections = [Connection(f"c{a}.d{b}", f"c{b}.in_d{a}") for a, b in edges]
    connections += [Connection(f"c{a}.s{b}_{k}", f"c{b}.in_s{a}_{k}") for a, b, k in soft]
    variables = {name: {} for name in names}
    for a, b in edges:
        variables[f"c{a}"][f"d{b}"] = Variable(f"d{b}", 0, "Real", "output", "discrete")
    for a, b, k in soft:
        variables[f"c{a}"][f"s{b}_{k}"] = Variable(f"s{b}_{k}", 0, "Real", "output", "continuous")
    system = System(tuple(Component(name, "Trajectory") for name in names), tuple(connections), (), 0.0)
    order = master.stepping_order(system, variables)
    late = [(a, b) for a, b, _ in soft]          # one entry per connection
    best = min(_violations(tuple(f"c{i}" for i in perm), late) for perm in itertools.permutations(range(n))
               if all(perm.index(a) < perm.index(b) for a, b in edges))
    assert _violations(order, late) == best
    first = min(perm for perm in itertools.permutations(range(n))
                if all(perm.index(a) < perm.index(b) for a, b in edges)
                and _violations(tuple(f"c{i}" for i in perm), late) == best)
    assert order == tuple(f"c{i}" for i in first)


def test_a_pair_joined_three_times_outweighs_two_single_connections():
    """c1 reads c0 three times; c0 reads c1 and c2, c2 reads c1, once each (continuous outputs).
    c0 first reads c0's three late (3); c1, c0, c2 reads two single ones late (2) and is the
    order.  Catches a pair weighed one more than its connections (then 4 against 4: c0, c2, c1
    wins the tie) or once whatever its count."""
    soft = [(0, 1), (0, 1), (0, 1), (1, 0), (1, 2), (2, 0)]
    names = ["c0", "c1", "c2"]
    connections = [Connection(f"c{a}.s{b}_{k}", f"c{b}.in_s{a}_{k}") for k, (a, b) in enumerate(soft)]
    variables = {name: {} for name in names}
    for k, (a, b) in enumerate(soft):
        variables[f"c{a}"][f"s{b}_{k}"] = Variable(f"s{b}_{k}", 0, "Real", "output", "continuous")
    system = System(tuple(Component(name, "Trajectory") for name in names), tuple(connections), (), 0.0)
    order = master.stepping_order(system, variables)
    assert _violations(order, soft) == 2
    assert order == ("c1", "c0", "c2")
