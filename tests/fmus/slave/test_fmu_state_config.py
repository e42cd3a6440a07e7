"""What fmi2DeSerializeFMUstate and fmi2SetFMUstate say when a state's header does not fit the
instance (fmus/slave/state_calls.py), word for word: another GUID, another layout, another
configuration with a parameter to name or with none (the digest alone) (issue 31: error paths'
messages naming what, the values and the time; seed 3601's [101] is the fallback's ``or``).
In process: fast."""
from __future__ import annotations

import pytest

from fmus.slave import state as fmustate
from fmus.slave.base import FmiError
from fmus.slave.state_format import DIGEST_SIZE
from tests.fmus.slave.test_fmu_state_data import _reframed, _running

MODEL = "Derivator"


@pytest.fixture
def running():
    """A Derivator after 4 steps of 1 ms (at t = 4 ms) and its state's bytes."""
    inst = _running(MODEL, steps=4)
    return inst, inst.serialize_state(inst.get_state())


def _refused(inst, data, call=None) -> str:
    before = inst.serialize_state(inst.get_state())
    with pytest.raises(FmiError) as refused:
        (call or inst.deserialize_state)(data)
    assert inst.serialize_state(inst.get_state()) == before, "a refused state changes nothing"
    return str(refused.value)


def test_another_guid_and_another_layout_are_named_with_both_values(running):
    """Catches the GUID or layout check dropped, or its message naming the wrong side."""
    inst, data = running
    assert _refused(inst, _reframed(data, guid="{other}")) == (
        "fmi2DeSerializeFMUstate: the state is of the FMU with GUID '{other}', this is '' (at t = 0.004 s); "
        "nothing was read")
    layout = type(inst.slave).STATE_LAYOUT   # 2 for the Derivator since its cascade (session 38)
    assert layout != 7
    assert _refused(inst, _reframed(data, layout=7)) == (
        f"fmi2DeSerializeFMUstate: state layout 7; {MODEL} reads layout {layout}; nothing was read")


def test_another_configuration_names_the_parameter_or_else_the_digest(running):
    """A state whose digest is not the instance's: with T = 2 ms in its values the refusal
    names T and both values; with the same parameters (only the digest forged) it says the
    digest differs.  Catches the fallback joined by "and" (the parameter's name lost, seed
    3601's [101]) or the fallback's text lost (an empty parenthesis)."""
    inst, data = running
    other = _running(MODEL, steps=4, T=2e-3)
    other_data = other.serialize_state(other.get_state())
    assert _refused(inst, other_data) == (
        "fmi2DeSerializeFMUstate: the FMU state was taken in another configuration (parameter T = 0.002 in the "
        f"state, 0.001 in this instance); {MODEL} refuses it (at t = 0.004 s); nothing was set")
    forged = _reframed(data, config=bytes(DIGEST_SIZE))
    assert _refused(inst, forged) == (
        "fmi2DeSerializeFMUstate: the FMU state was taken in another configuration (its configuration digest "
        f"differs); {MODEL} refuses it (at t = 0.004 s); nothing was set")
    live = inst.get_state()
    assert _refused(inst, fmustate.Snapshot(live.values, live.model, live.guid, bytes(DIGEST_SIZE)),
                    inst.set_state) == (
        "fmi2SetFMUstate: the FMU state was taken in another configuration (its configuration digest differs); "
        f"{MODEL} refuses it (at t = 0.004 s); nothing was set")
