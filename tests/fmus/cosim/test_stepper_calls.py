"""fmus/cosim/stepper.py's calls of one member (:func:`member_calls`) for an instance that offers
none of its own (an FMU, a user's Python instance), and :meth:`Stepper._run`, the loop that
runs them: inputs from the right slots, outputs to the right slots, and a refusal or an
exception inside a call reported as the instance's, at the time of its sub-step."""
from __future__ import annotations

import types

import pytest

from fmus.cosim.backends import CoSimulationError
from fmus.cosim.stepper import Call, Stepper, member_calls
from fmus.status import RunError, RunStatus


class _Plain:
    """An instance with the back ends' calls only (no ``step_calls``), recording what it is given."""

    def __init__(self, name, outputs, fail=None):
        self.name, self.outputs, self.fail = name, outputs, fail
        self.inputs, self.steps = [], []

    def set_inputs(self, values):
        self.inputs.append(list(values))

    def do_step(self, t, h):
        self.steps.append((t, h))
        if self.fail is not None and len(self.steps) == 2:
            raise self.fail

    def get_outputs(self):
        return list(self.outputs)

    def step_refused(self, t):
        return CoSimulationError(self.name, t, "refused by its own word", RunError(RunStatus.REFUSED, "own", self.name, t))


def test_a_plain_instances_calls_move_its_slots_and_name_it():
    """Catches an instance's inputs taken from other slots or in another order, its outputs
    written to other slots, or the calls naming another object than the instance (the loop's
    errors name ``calls.instance``)."""
    values = [0.5, 1.5, 2.5, 3.5, 4.5, 5.5]
    inst = _Plain("user", [-1.0, -2.0])
    calls = member_calls(inst, (4, 0, 2), (1, 2))
    assert calls.instance is inst
    calls.pull(values)
    assert inst.inputs == [[4.5, 0.5, 2.5]]
    assert calls.step(0.25, 0.125) is None and inst.steps == [(0.25, 0.125)]
    values[calls.out] = calls.read(calls.source)
    assert values == [0.5, -1.0, -2.0, 3.5, 4.5, 5.5]
    assert member_calls(inst, (), (3,)).pull is None


def _program(members, substeps=1, h=0.1):
    """The calls of ``members`` [(instance, in slots, out slots)] over ``substeps`` sub-steps."""
    calls = []
    for j in range(substeps):
        for inst, ins, outs in members:
            c = member_calls(inst, ins, outs)
            calls.append(Call(c.pull, None, c.step, j * h / substeps, h / substeps, c.read, c.source, c.out,
                              c.instance))
    return calls


def _run(calls, values, t):
    stepper = types.SimpleNamespace(values=values)
    for k, call in enumerate(calls):
        calls[k] = call._replace(reads=values)
    Stepper._run(stepper, calls, t)


def test_the_loop_chains_outputs_to_the_next_members_inputs():
    """Catches a member's outputs stored after the next member read its inputs, or into other
    slots than its own."""
    a, b = _Plain("a", [7.0]), _Plain("b", [8.0, 9.0])
    values = [1.0, 0.0, 0.0, 0.0]
    _run(_program([(a, (0,), (1,)), (b, (1, 0), (2, 3))]), values, 2.0)
    assert b.inputs == [[7.0, 1.0]] and values == [1.0, 7.0, 8.0, 9.0]
    assert a.steps == b.steps == [(2.0, 0.1)]


def test_an_exception_in_a_call_is_the_instances_error_at_its_sub_steps_time():
    """Catches an exception inside a plain instance's step reported without the instance's
    name, at the step's start instead of its sub-step's, or escaping as itself."""
    ok, bad = _Plain("ok", [1.0]), _Plain("bad", [2.0], fail=ValueError("tau_l = nan is not finite"))
    with pytest.raises(CoSimulationError) as caught:
        _run(_program([(ok, (), (0,)), (bad, (0,), (1,))], substeps=4, h=0.4), [0.0, 0.0], 1.0)
    assert (caught.value.instance, caught.value.time, caught.value.message) == ("bad", 1.1, "tau_l = nan is not finite")
    assert len(ok.steps) == 2 and len(bad.steps) == 2


def test_a_step_that_returns_false_raises_the_instances_own_refusal():
    """Catches a step returning False (an in-process slave's refusal) passed over, or reported
    without the instance's own record."""
    inst = _Plain("drive", [1.0])
    call = _program([(inst, (), (0,))])[0]
    calls = [call._replace(step=lambda t, h: False)]
    with pytest.raises(CoSimulationError) as caught:
        _run(calls, [0.0], 0.3)
    assert caught.value.run_error == RunError(RunStatus.REFUSED, "own", "drive", 0.3)


def test_a_step_refused_in_a_later_sub_step_is_reported_at_that_sub_steps_time():
    """Four sub-steps of 0.1 s from t = 1.0: the second (from 1.1) refused names 1.1, as the
    exception's report does, and the sub-steps after it are not taken.  Catches the refusal's
    time taken at the step's start or with the offset subtracted (seed 4001's survivor [7],
    ``t - offset``: 0.9)."""
    inst = _Plain("drive", [1.0])
    steps = []

    def refusing(t, h):
        steps.append((t, h))
        return False if len(steps) == 2 else None

    calls = [call._replace(step=refusing) for call in _program([(inst, (), (0,))], substeps=4, h=0.4)]
    with pytest.raises(CoSimulationError) as caught:
        _run(calls, [0.0], 1.0)
    assert steps == [(1.0, 0.1), (1.1, 0.1)]
    assert caught.value.time == 1.1 and caught.value.run_error == RunError(RunStatus.REFUSED, "own", "drive", 1.1)


def test_an_instance_whose_class_offers_step_calls_is_given_its_own_calls_with_its_slots():
    """The rule of :func:`member_calls`: a class with ``step_calls`` makes the member's calls,
    given the instance and both slot lists as passed; a wrapper that only delegates the
    attribute (not its class) gets the generic calls.  Catches the rule looked up on another
    object (training seed 4322 [15]: on ``out_slots``, every in-process slave taken the slow way)."""
    asked = []

    class Own:
        def step_calls(self, in_slots, out_slots):
            asked.append((self, in_slots, out_slots))
            return ("pull", "step", "read", "source", "out", self)

    inst = Own()
    assert tuple(member_calls(inst, (4, 0), (1, 2))) == ("pull", "step", "read", "source", "out", inst)
    assert asked == [(inst, (4, 0), (1, 2))]

    class Wrapper:
        def __init__(self, inner):
            self.inner = inner
            self.step_calls = inner.step_calls       # on the instance, not its class

        def set_inputs(self, values):
            pass

        def do_step(self, t, h):
            return True

        def get_outputs(self):
            return [0.0]

    wrapper = Wrapper(Own())
    calls = member_calls(wrapper, (), (3,))
    assert calls.step == wrapper.do_step and calls.instance is wrapper and asked == [(inst, (4, 0), (1, 2))]
