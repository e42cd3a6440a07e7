"""An algebraic loop named by every connection on it (issue 31; session 43's training seed
4322 [4] in fmus/cosim/master.py ``_check_hard_loops``): sampled outputs that need each
other's value within one step are refused before any step, and the refusal lists the loop's
connections, each once, and no other (docs/master.md)."""
from __future__ import annotations

import pytest

from fmus.cosim.master import AlgebraicLoopError, simulate
from fmus.cosim.system import Component, Connection, System

PREFIX = ("algebraic loop: these connections need each other's value within one step "
          "(sampled or direct-feedthrough outputs): ")


def _ring(names, extra=()):
    """Derivators in a ring, each one's dq1 into the next one's q1 (sampled: a hard loop);
    ``extra`` connections off the ring."""
    loop = tuple(Connection(f"{a}.dq1", f"{b}.q1") for a, b in zip(names, names[1:] + names[:1]))
    components = tuple(Component(n, "Derivator", {}) for n in names) + (
        Component("traj", "Trajectory", {"kind": "thesis_circle"}),)
    return System(components, loop + tuple(extra), (f"{names[0]}.dq1",), stop_time=0.01), loop


@pytest.mark.parametrize("names", [["d1", "d2"], ["d1", "d2", "d3"], ["a", "c", "b", "d"]])
def test_an_algebraic_loop_is_refused_naming_each_of_its_connections_once(names):
    """Rings of 2, 3 and 4 sampled components, fed from a trajectory off the ring: the error
    names exactly the ring's connections, each once, not the feed.
    Catches the cycle cut to its last two components (one link named) or a link missed."""
    system, loop = _ring(names, extra=(Connection("traj.x_d", f"{names[0]}.q2"),))
    with pytest.raises(AlgebraicLoopError) as refused:
        simulate(system)
    message = str(refused.value)
    assert message.startswith(PREFIX)
    links = message[len(PREFIX):].split("; ")
    assert sorted(links) == sorted(f"{c.source} -> {c.target}" for c in loop)
