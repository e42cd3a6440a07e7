"""Jacobi coupling with a multi-rate group (fmus/cosim/stepper.py, module docstring): every
member reads the values at the step's start, except that inside a group of n sub-steps its
members read the group's snapshot at each sub-step's start (the step's start values, with the
group's own outputs as they are at that sub-step's start).

Held against a reference written here from that text alone, with linear discrete
components whose outputs depend on every input and on the sub-step length, so that any
value read at another moment, or a snapshot taken at another member or sub-step, changes the
rows.
"""
from __future__ import annotations

import numpy as np
import pytest

from fmus.cosim.backends import Variable
from fmus.cosim.stepper import Stepper
from fmus.cosim.system import Component, Connection, System

H = 0.1


class _Linear:
    """y <- a y + sum(w_i u_i) + dt (dt: the sub-step's length), one output."""

    def __init__(self, name: str, inputs: tuple, a: float, weights: tuple):
        self.name, self.inputs, self.a, self.weights = name, inputs, a, weights
        self.variables = {"y": Variable("y", 0, "Real", "output", "discrete")}
        self.variables.update({u: Variable(u, k + 1, "Real", "input", "continuous") for k, u in enumerate(inputs)})
        self.y, self.u, self.bound = 0.0, dict.fromkeys(inputs, 0.0), ()
        self.calls = []

    def bind(self, inputs, outputs):
        self.bound = tuple(v.name for v in inputs)
        assert [v.name for v in outputs] == ["y"]

    def enter_initialization(self, parameters, start_time):
        self.y = 0.1 * (1 + len(self.name))

    def exit_initialization(self):
        pass

    def set_inputs(self, values):
        self.u.update(zip(self.bound, values))

    def get_outputs(self):
        return [self.y]

    def do_step(self, t, h):
        self.calls.append((round(t, 12), h))
        self.y = self.a * self.y + sum(w * self.u[u] for w, u in zip(self.weights, self.inputs)) + h


#: name, substeps, its inputs and where they come from, a, weights
SPEC = [("p", 1, {"u1": "q", "u2": "r"}, 0.5, (0.3, -0.2)),
        ("q", 3, {"u1": "p", "u2": "r"}, 0.8, (0.25, 0.5)),
        ("r", 3, {"u1": "q", "u2": "s"}, -0.4, (0.6, 0.1)),
        ("s", 2, {"u1": "r"}, 0.9, (-0.7,))]


def _system():
    components = tuple(Component(name, "Trajectory", substeps=n) for name, n, _, _, _ in SPEC)
    connections = tuple(Connection(f"{src}.y", f"{name}.{u}") for name, _, ins, _, _ in SPEC for u, src in ins.items())
    instances = {name: _Linear(name, tuple(ins), a, w) for name, _, ins, a, w in SPEC}
    system = System(components, connections, tuple(f"{name}.y" for name, *_ in SPEC), 0.5, H)
    return system, instances


def _reference(steps: int) -> np.ndarray:
    """Groups (consecutive equal sub-step counts above 1): p | q r (3) | s (2)."""
    spec = {name: (n, ins, a, w) for name, n, ins, a, w in SPEC}
    y = {name: 0.1 * (1 + len(name)) for name in spec}
    rows = [[y[name] for name in spec]]
    for _ in range(steps):
        held = dict(y)
        for group in (["p"], ["q", "r"], ["s"]):
            n = spec[group[0]][0]
            reads = dict(held)
            for _j in range(n):
                if _j > 0:
                    reads.update({m: y[m] for m in group})     # the group's outputs at this sub-step's start
                for m in group:
                    _, ins, a, w = spec[m]
                    y[m] = a * y[m] + sum(wk * reads[src] for wk, src in zip(w, ins.values())) + H / n
        rows.append([y[name] for name in spec])
    return np.array(rows)


def test_jacobi_with_multi_rate_groups_reads_the_snapshots_the_docstring_names():
    """Catches a snapshot taken at another member than a sub-step's first, a group's reads
    not refreshed with its own outputs at each sub-step (or refreshed with others'), the
    arguments of the snapshot confused, and any member reading values of the current step."""
    system, instances = _system()
    stepper = Stepper(system, instances, tuple(c.name for c in system.components), jacobi=True)
    stepper.initialize(0.0)
    rows = [stepper.row()]
    for _ in range(system.steps):
        stepper.step()
        rows.append(stepper.row())
    expected = _reference(system.steps)
    np.testing.assert_allclose(np.array(rows), expected, rtol=1e-13, atol=1e-15)
    assert instances["q"].calls[:3] == [(0.0, H / 3), (round(H / 3, 12), H / 3), (round(2 * H / 3, 12), H / 3)]


@pytest.mark.parametrize("jacobi", [False, True])
def test_the_reference_differs_from_gauss_seidel_so_the_test_can_fail(jacobi):
    """The rows under Gauss-Seidel (members reading outputs of the current step) are not the
    Jacobi reference: the reference is not satisfied by any coupling."""
    system, instances = _system()
    stepper = Stepper(system, instances, tuple(c.name for c in system.components), jacobi=jacobi)
    stepper.initialize(0.0)
    for _ in range(3):
        stepper.step()
    assert np.allclose(stepper.row(), _reference(3)[-1], rtol=1e-13) is jacobi
