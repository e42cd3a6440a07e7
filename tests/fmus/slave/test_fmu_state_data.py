"""A serialised FMU state is data, not code (issue 30.1; docs/state.md).

Bytes from elsewhere — random, truncated, altered (with or without a recomputed checksum),
another model's, another configuration's, or a pickle that would run a command — are
refused with an error naming what did not match, change nothing, and never run code.  A
state that is accepted continues as the model would: no NaN with a successful step.
"""
from __future__ import annotations

import hashlib
import math
import os
import struct
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fmus.slave import state as fmustate
from fmus.slave import state_format as stateformat
from fmus.slave.base import FmiError
from fmus.cosim.backends import CoSimulationError, InProcessInstance, _FmuInstance
from fmus.slave.registry import SLAVES

MODELS = tuple(SLAVES)
STEPS = 20


def _real_outputs(inst):
    return [v.name for v in inst.variables.values() if v.causality == "output" and v.type == "Real"]


def _running(model: str, steps: int = STEPS, **parameters) -> InProcessInstance:
    inst = InProcessInstance(model, model.lower())
    inst.initialize(parameters, 0.0)
    for k in range(steps):
        inst.do_step(k * 1e-3, 1e-3)
    return inst


_STATES = {}


def _state_bytes(model: str) -> bytes:
    """A mid-run state of ``model`` (default parameters), serialised (cached)."""
    if model not in _STATES:
        inst = _running(model)
        _STATES[model] = inst.serialize_state(inst.get_state())
    return _STATES[model]


def _reframed(data: bytes, tree=None, **header) -> bytes:
    """``data`` re-encoded with ``tree`` and header fields replaced, with a valid checksum:
    what a deliberate forger writes."""
    decoded = fmustate.read(data)
    fields = {f: getattr(decoded.header, f) for f in ("model", "guid", "config", "layout")}
    fields.update(header)
    return stateformat.encode(stateformat.Header(**fields), decoded.tree if tree is None else tree)


def _framed(body: bytes) -> bytes:
    """Any body in a well-formed frame (magic, version, length, checksum)."""
    head = stateformat.MAGIC + struct.pack("<IQ", stateformat.FORMAT_VERSION,
                                           len(stateformat.MAGIC) + 12 + len(body) + 32)
    return head + body + hashlib.sha256(head + body).digest()


def _continues_cleanly(inst, k0: int = STEPS, steps: int = 5) -> None:
    """Steps after an accepted state: each is refused with a message or gives finite outputs."""
    names = _real_outputs(inst)
    for k in range(k0, k0 + steps):
        try:
            inst.do_step(k * 1e-3, 1e-3)
        except CoSimulationError as exc:
            assert exc.message, "a refusal names its reason"
            return
        values = [getattr(inst.slave, n) for n in names]
        assert all(math.isfinite(v) for v in values), f"fmi2OK with non-finite outputs {dict(zip(names, values))}"


# --- round trips ------------------------------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_a_state_read_back_continues_bit_for_bit_in_any_instance_of_the_model(model):
    """Into the same instance, a fresh one (instantiated only) and one initialised and run
    elsewhere: the continuation equals the original's to the bit.  A reader that dropped or
    mis-placed any field (an array copied into the wrong object, a shared buffer unshared)
    would continue differently."""
    source = _running(model)
    data = source.serialize_state(source.get_state())
    names = _real_outputs(source)

    def continuation(inst):
        rows = []
        for k in range(STEPS, STEPS + 10):
            inst.do_step(k * 1e-3, 1e-3)
            rows.append([getattr(inst.slave, n) for n in names])
        return np.array(rows)

    reference = continuation(source)
    fresh = InProcessInstance(model, "fresh")
    elsewhere = _running(model, steps=3)
    for target in (source, fresh, elsewhere):
        target.set_state(target.deserialize_state(data))
        np.testing.assert_array_equal(continuation(target), reference)


def test_a_restored_derivator_steps_its_kernel_buffer():
    """The derivator's state lives in the buffer the C kernel and the compiled loop read:
    after fmi2SetFMUstate (a live snapshot or bytes read back) a step must advance the
    restored buffer, not the one of the instance before the restore."""
    from controller import fastderivator

    inst = _running("Derivator")
    for state in (inst.get_state(), inst.deserialize_state(inst.serialize_state(inst.get_state()))):
        before = inst.slave.derivator.buf
        inst.set_state(state)
        derivator = inst.slave.derivator
        kept = before.copy()
        inst.slave.q1, inst.slave.q2 = 0.3, -0.2
        inst.do_step(inst.slave._next_time, 1e-3)
        assert fastderivator.views(derivator.buf)[1][-1].tolist() == [0.3, -0.2]
        if before is not derivator.buf:
            np.testing.assert_array_equal(before, kept)


@pytest.mark.parametrize("model", ["Derivator", "ClosedLoop", "ControlChain"])
def test_a_state_of_the_derivators_step_matrix_layout_is_refused(model):
    """Layout 1 held the derivator's dense step matrix where layout 2 holds its sections: the
    models that carry a derivator refuse a layout-1 state, naming both layouts, before reading
    it.  Catches a layout change whose old states would be read as the new buffer."""
    import importlib

    cls = getattr(importlib.import_module(f"fmus.slaves.parcosim_{model.lower()}"), model)
    assert cls.STATE_LAYOUT == 2
    data = _reframed(_state_bytes("Derivator"), model=model, layout=1)
    with pytest.raises(FmiError, match=rf"state layout 1; {model} reads layout 2; nothing was read"):
        cls._fmu_state_from_bytes(data)


def test_the_format_keeps_shared_arrays_shared():
    """The drive's controller buffer is one array reached from two places; after a read the
    two places must still be one array (a copy each would let the fast step and the design
    object drift apart)."""
    drive = _running("DCMotorDrive")
    restored = drive.slave.deserialize_fmu_state(drive.serialize_state(drive.get_state())).values["drive"]
    assert restored._controller_buf is restored.controller.buf


# --- what is refused ---------------------------------------------------------------------


@pytest.mark.parametrize("source", MODELS)
def test_another_models_state_is_refused_even_with_a_forged_header(source):
    data = _state_bytes(source)
    for target_model in MODELS:
        if target_model == source:
            continue
        target = _running(target_model, steps=2)
        before = target.serialize_state(target.get_state())
        with pytest.raises(FmiError, match=f"a state of '{source}', not of {target_model}"):
            target.deserialize_state(data)
        forged = _reframed(data, model=target_model, config=target.slave._config_digest())
        with pytest.raises(FmiError, match="fmi2DeSerializeFMUstate: .*nothing was read"):
            target.deserialize_state(forged)
        assert target.serialize_state(target.get_state()) == before, "a refused state changes nothing"


def test_a_live_state_of_another_model_is_refused():
    drive, observer = _running("DCMotorDrive"), _running("CurrentObserver")
    with pytest.raises(FmiError, match="the FMU state of a DCMotorDrive cannot be set in a CurrentObserver"):
        observer.set_state(drive.get_state())
    with pytest.raises(FmiError, match="a dict is not an FMU state of CurrentObserver"):
        observer.set_state({"R": 1.0})


def test_a_state_of_another_configuration_is_refused_once_initialised():
    """The issue's case: a Derivator restored from a T = 2 ms instance ran as if T were
    2 ms at 1 ms steps (0.5 rad/s estimated for 1 rad/s)."""
    slow = InProcessInstance("Derivator", "slow")
    slow.initialize({"T": 2e-3}, 0.0)
    slow.do_step(0.0, 2e-3)
    data = slow.serialize_state(slow.get_state())
    live = slow.get_state()
    fast = _running("Derivator", steps=1)
    with pytest.raises(FmiError, match=r"another configuration \(parameter T = 0.002 in the state, 0.001 in this "
                                       r"instance\)"):
        fast.deserialize_state(data)
    with pytest.raises(FmiError, match="parameter T = 0.002 in the state"):
        fast.set_state(live)
    # Before initialisation the parameters are still free: the state brings its own.
    fresh = InProcessInstance("Derivator", "fresh")
    fresh.set_state(fresh.deserialize_state(data))
    assert fresh.slave.T == 2e-3
    fresh.do_step(2e-3, 2e-3)
    with pytest.raises(CoSimulationError, match="does not divide the sample time T = 0.002"):
        fresh.do_step(4e-3, 1.5e-3)


def test_the_configuration_of_a_state_follows_parameters_set_after_a_restore():
    """A state taken before initialisation, set after it, opens the parameters again: the
    digest the next snapshot carries is the new configuration's (a digest kept from before
    would let a state of T = 1 ms into a T = 2 ms instance)."""
    inst = InProcessInstance("Derivator", "d")
    inst.enter_initialization({}, 0.0)
    before = inst.get_state()
    inst.exit_initialization()
    one_ms = inst.get_state().config
    inst.set_state(before)
    inst.slave.T = 2e-3
    inst.exit_initialization()
    two_ms = inst.get_state().config
    assert two_ms != one_ms
    assert two_ms == fmustate.config_digest("Derivator", fmustate.parameter_values(inst.slave))


@pytest.mark.parametrize("model", ["Derivator", "FiveBarPlant", "PositionController"])
def test_a_non_finite_value_is_refused_by_its_place(model):
    """One float of the state set to NaN (or infinity) with a recomputed checksum: refused,
    naming where, unless the instance holds the same non-finite value there (the table's
    marks outside the workspace)."""
    data = _state_bytes(model)
    tree = fmustate.read(data).tree
    paths = list(_float_places(tree, ""))
    assert paths, "the state holds floats"
    for path, container, key in paths[:: max(1, len(paths) // 12)]:
        for bad in (math.nan, math.inf):
            old = container[key]
            container[key] = bad
            target = _running(model, steps=2)
            with pytest.raises(FmiError, match="not a finite number"):
                target.deserialize_state(_reframed(data, tree))
            container[key] = old


def _float_places(node, path):
    """(path, container, key) of each float leaf of a read tree that holds a finite value."""
    items = node.fields.items() if isinstance(node, stateformat.ObjectRecord) else \
        node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        if type(value) is float and math.isfinite(value):
            yield f"{path}.{key}", (node.fields if isinstance(node, stateformat.ObjectRecord) else node), key
        elif isinstance(value, (dict, list, stateformat.ObjectRecord)):
            yield from _float_places(value, f"{path}.{key}")


def test_configuration_inside_the_state_cannot_be_forged():
    """The plant's integrator settings are configuration (a frozen object built from the
    parameters): a forged state with 10**9 RK4 substeps (one step would take hours) or
    another Baumgarte gain is refused, naming the place, before anything is set."""
    data = _state_bytes("FiveBarPlant")
    tree = fmustate.read(data).tree
    settings_record = tree["sim"].fields["settings"]
    assert settings_record.tag == "plant.simulator.IntegratorSettings"
    target = _running("FiveBarPlant", steps=2)
    for name, forged in (("substeps", 10 ** 9), ("baumgarte", 1e9)):
        old = settings_record.fields[name]
        settings_record.fields[name] = forged
        with pytest.raises(FmiError, match=r"sim\.settings: the state's plant.simulator.IntegratorSettings differs"):
            target.deserialize_state(_reframed(data, tree))
        settings_record.fields[name] = old
    target.set_state(target.deserialize_state(_reframed(data, tree)))   # unforged: taken


@pytest.mark.parametrize("model, holder, field, layout, coefficient, run_state", [
    ("Derivator", "derivator", "buf", "V_STATES", "V_RATE", "V_STARTED"),
    ("BalanceController", "controller", "buf", "B_STATES", "B_GAIN", "B_X_HAT"),
    ("PositionController", "controller", "_buf", "BUF_MODEL", "BUF_KP", "BUF_INTEGRAL")])
def test_the_configuration_words_of_a_kernel_buffer_cannot_be_forged(model, holder, field, layout, coefficient,
                                                                     run_state):
    """The compiled kernels index arrays and loop with words of their buffers (the
    derivator's number of states, the balance controller's kept-state indices, the table's
    cells) and compute with others (gains, matrices): a forged state that changed a layout
    word would make a kernel read or write outside its arrays, a coefficient would change the
    design.  Both refused, naming the word; so is a buffer of another shape.  A run-state
    word (the filter's start flag, the estimate, the integral) is taken."""
    import importlib

    kernel = importlib.import_module({"Derivator": "controller.fastderivator",
                                      "BalanceController": "controller.fastbalance",
                                      "PositionController": "controller.law"}[model])
    data = _state_bytes(model)
    tree = fmustate.read(data).tree
    buffer = tree[holder].fields[field]
    target = _running(model, steps=2)
    for word in (layout, coefficient):
        index = getattr(kernel, word) if isinstance(word, str) else word(kernel, buffer)
        forged = buffer.copy()
        forged[index] += 1000.0
        tree[holder].fields[field] = forged
        with pytest.raises(FmiError, match=rf"{holder}\.{field}\[{index}\]: the state changes a configuration word"):
            target.deserialize_state(_reframed(data, tree))
    tree[holder].fields[field] = np.concatenate([buffer, buffer])
    with pytest.raises(FmiError, match=rf"{holder}\.{field}: an array of shape"):
        target.deserialize_state(_reframed(data, tree))
    forged = buffer.copy()
    forged[getattr(kernel, run_state)] += 0.5
    tree[holder].fields[field] = forged
    target.set_state(target.deserialize_state(_reframed(data, tree)))   # run state: taken


def test_a_state_cannot_name_code_into_the_instance():
    """An object record or an opaque value naming other code (os.system) where the instance
    holds something else is refused by name, and reading it imports nothing."""
    data = _state_bytes("Trajectory")
    tree = fmustate.read(data).tree
    target = _running("Trajectory", steps=2)
    own = tree["trajectory"]
    for forged in (stateformat.Opaque("function:posix.system"), stateformat.ObjectRecord("posix.system", {}),
                   stateformat.ObjectRecord("aaa.Evil", dict(own.fields))):   # sorts before the instance's class
        tree2 = dict(tree)
        tree2["trajectory"] = forged
        with pytest.raises(FmiError, match="trajectory: the state"):
            target.deserialize_state(_reframed(data, tree2))


def _inner_snapshots(node):
    """The inner slaves' states (records tagged as snapshots) in a read tree."""
    if isinstance(node, stateformat.ObjectRecord):
        if node.tag == fmustate.SNAPSHOT_TAG:
            yield node
            return
        node = node.fields
    items = node.values() if isinstance(node, dict) else node if isinstance(node, (list, tuple)) else ()
    for item in items:
        yield from _inner_snapshots(item)


def test_reading_any_state_imports_and_runs_nothing(tmp_path):
    """The issue's exploit: pickle bytes naming ``fmus.slave.base`` + ``os.system``.  In a fresh
    process the crafted bytes, and a well-formed state naming subprocess.Popen and ctypes,
    are refused, run nothing and leave sys.modules as it was: the reader never imports."""
    marker = tmp_path / "ran"
    script = f"""
import pickle, sys, pickletools
from fmus.slave.state_format import Header, ObjectRecord, Opaque, encode
from fmus.slaves.parcosim_trajectory import Trajectory
from fmus.slave.base import FmiError

class Evil:
    def __reduce__(self):
        import os
        return os.system, ("touch {marker}",)

old = b"parcosim-fmu-state-1\\nTrajectory\\n" + pickle.dumps(Evil(), protocol=4)
named = encode(Header("Trajectory", "", bytes(32), 1), {{"x": ObjectRecord("subprocess.Popen", {{"args": "touch {marker}"}}),
                                                        "y": Opaque("module:ctypes")}})
slave = Trajectory(instance_name="t")
warm_up = encode(Header("Trajectory", "", bytes(32), 1), {{"x": 1.0}})
try:   # the first refusal may import parts of our own code (building a template): not the state's doing
    slave.deserialize_fmu_state(warm_up)
except FmiError:
    pass
modules = set(sys.modules)
for data in (old, named):
    try:
        slave.deserialize_fmu_state(data)
    except FmiError as exc:
        print("refused:", exc)
    else:
        print("ACCEPTED")
print("new modules:", sorted(set(sys.modules) - modules))
"""
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=os.getcwd(), timeout=120)
    assert run.returncode == 0, run.stderr
    assert "ACCEPTED" not in run.stdout
    assert run.stdout.count("refused:") == 2
    assert "not a serialised parcosim FMU state" in run.stdout
    assert "new modules: []" in run.stdout
    assert not marker.exists()


def test_ints_round_trip_over_the_whole_64_bit_range_and_beyond_it_are_refused_by_place():
    """Catches a state format that truncates 64-bit ints or accepts larger ones silently."""
    header = stateformat.Header("M", "", bytes(32), 1)
    values = {"low": -2 ** 63, "high": 2 ** 63 - 1, "minus": -1000, "list": [-2 ** 62, 7]}
    assert stateformat.decode(stateformat.encode(header, values))[1] == values
    builder = fmustate._TreeBuilder()
    assert builder.node(values, "") == values
    for wide in (2 ** 63, -2 ** 63 - 1):
        with pytest.raises(TypeError, match=r"\['x'\]\[1\]: the int .* does not fit the state format's 64 bits"):
            fmustate._TreeBuilder().node({"x": [0, wide]}, "")


# --- properties over any bytes -------------------------------------------------------------

_PROPERTY = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _refused_or_clean(model: str, data: bytes) -> None:
    """Deserialising ``data`` into a running ``model`` raises FmiError and changes nothing,
    or gives a state whose continuation is clean."""
    target = _running(model, steps=2)
    before = target.serialize_state(target.get_state())
    try:
        state = target.deserialize_state(data)
    except FmiError as exc:
        assert str(exc).startswith("fmi2DeSerializeFMUstate: ")
        assert target.serialize_state(target.get_state()) == before
        return
    target.set_state(state)
    _continues_cleanly(target, k0=int(round(target.slave._next_time / 1e-3)))


@_PROPERTY
@given(model=st.sampled_from(MODELS), data=st.binary(max_size=300))
def test_random_bytes_are_refused(model, data):
    """Catches a state parser that accepts, or crashes on, random bytes."""
    with pytest.raises(FmiError, match="fmi2DeSerializeFMUstate: "):
        _running(model, steps=0).deserialize_state(data)


@_PROPERTY
@given(body=st.binary(max_size=300))
def test_random_bodies_in_a_valid_frame_are_refused_by_the_reader(body):
    """Past the magic and the checksum, the reader meets arbitrary tags, counts and lengths:
    it refuses them by name (no IndexError, MemoryError or RecursionError escapes)."""
    with pytest.raises(FmiError, match="fmi2DeSerializeFMUstate: "):
        _running("CurrentObserver", steps=0).deserialize_state(_framed(body))


@_PROPERTY
@given(model=st.sampled_from(MODELS), cut=st.floats(0.0, 1.0, exclude_max=True))
def test_truncated_states_are_refused(model, cut):
    """Catches a state parser that accepts, or crashes on, a truncated state."""
    data = _state_bytes(model)
    with pytest.raises(FmiError, match="truncated|not a serialised"):
        _running(model, steps=0).deserialize_state(data[:int(cut * len(data))])


def test_every_prefix_shorter_than_the_frame_is_refused_as_not_a_state():
    """The magic and a few bytes, up to a whole header without its checksum: refused by name
    before any field is read (a reader that unpacked the version and length from fewer bytes
    would raise struct.error, not the refusal)."""
    data = _state_bytes("Trajectory")
    target = _running("Trajectory", steps=0)
    frame = len(stateformat.MAGIC) + 12 + stateformat.DIGEST_SIZE
    for n in range(frame):
        with pytest.raises(FmiError, match="not a serialised parcosim FMU state"):
            target.deserialize_state(data[:n])


@_PROPERTY
@given(model=st.sampled_from(MODELS), where=st.floats(0.0, 1.0, exclude_max=True), flip=st.integers(1, 255))
def test_an_altered_byte_is_refused_by_the_checksum(model, where, flip):
    data = bytearray(_state_bytes(model))
    data[int(where * len(data))] ^= flip
    with pytest.raises(FmiError, match="checksum|not a serialised|format version|says it has"):
        _running(model, steps=0).deserialize_state(bytes(data))


@_PROPERTY
@given(model=st.sampled_from(["Derivator", "FiveBarPlant", "DCMotorDrive", "Trajectory", "BalanceController",
                              "WheeledPendulum", "CurrentObserver"]),
       where=st.floats(0.0, 1.0, exclude_max=True), flip=st.integers(1, 255))
def test_a_forged_state_is_refused_or_continues_cleanly(model, where, flip):
    """A byte altered and the checksum recomputed (a deliberate forger): the reader refuses
    it, or the state it gives steps with finite outputs or a named refusal — never NaN with
    fmi2OK, never an exception other than the refusal."""
    decoded_len = len(_state_bytes(model)) - 32
    body = bytearray(_state_bytes(model)[:decoded_len])
    body[len(stateformat.MAGIC) + 12 + int(where * (decoded_len - len(stateformat.MAGIC) - 12))] ^= flip
    _refused_or_clean(model, bytes(body) + hashlib.sha256(body).digest())


@pytest.mark.parametrize("model", ["Derivator", "FiveBarPlant", "DCMotorDrive", "Trajectory", "BalanceController",
                                   "WheeledPendulum", "CurrentObserver", "PositionController"])
def test_a_state_whose_arrays_name_another_dtype_is_refused_and_changes_nothing(model):
    """Each array's dtype forged in turn ('<f8' -> '<g8', the checksum recomputed): refused
    with the instance unchanged.  Found by the property above: the plant's kernel binding was
    shared by the template a state is laid over, so a refused state had written its scratch."""
    good = _state_bytes(model)[:-32]
    places = [k for k in range(len(good)) if good.startswith(b"<f8", k)]
    assert places, "the state holds float64 arrays"
    for k in places:
        body = good[:k] + b"<g8" + good[k + 3:]
        _refused_or_clean(model, body + hashlib.sha256(body).digest())


# --- through the FMI wrapper ---------------------------------------------------------------

from tests.fmus.slave.test_fmu_state import system_fmus  # noqa: E402,F401 - the ClosedLoop and ControlChain FMUs (a fixture)


@pytest.mark.parametrize("model", ["ClosedLoop", "ControlChain"])
def test_a_system_fmu_refuses_foreign_truncated_and_altered_states(model, system_fmus):
    """The FMUs that contain a system: their own state (every inner slave's) reads back; the
    other system FMU's state, a truncated or altered one, and one whose inner values were
    forged to NaN are fmi2Error; the instance then steps on."""
    from fmpy.fmi1 import FMICallException

    other = {"ClosedLoop": "ControlChain", "ControlChain": "ClosedLoop"}[model]
    insts = {name: _FmuInstance(system_fmus[name], name) for name in (model, other)}
    for each in insts.values():
        each.initialize({}, 0.0)
    inst = insts[model]
    own = inst.serialize_state(inst.get_state())
    foreign = insts[other].serialize_state(insts[other].get_state())
    decoded = fmustate.read(own)
    tree = decoded.tree
    values = next(_inner_snapshots(tree["core"])).fields["values"]
    float_name = next(k for k, v in values.items() if type(v) is float and math.isfinite(v))
    values[float_name] = math.nan
    forged = _reframed(own, tree)
    altered = bytearray(own)
    altered[len(own) // 2] ^= 0x55
    for data, why in ((foreign, f"a state of '{other}', not of {model}"), (own[:len(own) // 3], "truncated"),
                      (bytes(altered), "checksum"), (forged, "not a finite number")):
        with pytest.raises(FMICallException) as info:
            inst.deserialize_state(data)
        assert info.value.status == 3
        assert why in inst.messages[-1], inst.messages[-1]
    restored = inst.deserialize_state(own)
    inst.set_state(restored)
    inst.free_state(restored)
    inst.do_step(0.0, 1e-3)
    for each in insts.values():
        each.close()


def test_the_fmu_refuses_foreign_states_and_states_of_other_instances(built_fmus, tmp_path):
    """Through parcosim's FMI wrapper (fmpy): the pickle exploit, random bytes and another
    FMU's state give fmi2Error (not fmi2Fatal, no crash, no command run); a state pointer of
    another instance is refused; the instance still steps afterwards."""
    from fmpy.fmi1 import FMICallException

    marker = tmp_path / "ran"
    plant = _FmuInstance(built_fmus["FiveBarPlant"], "plant")
    plant.initialize({}, 0.0)
    plant.do_step(0.0, 1e-3)
    other = _FmuInstance(built_fmus["FiveBarPlant"], "other")
    other.initialize({}, 0.0)
    drive = _FmuInstance(built_fmus["DCMotorDrive"], "drive")
    drive.initialize({}, 0.0)
    drive_state = drive.serialize_state(drive.get_state())
    import pickle

    class Evil:
        def __reduce__(self):
            return os.system, (f"touch {marker}",)

    exploit = b"parcosim-fmu-state-1\nFiveBarPlant\n" + pickle.dumps(Evil(), protocol=4)
    for data, why in ((exploit, "not a serialised parcosim FMU state"), (os.urandom(200), "not a serialised"),
                      (drive_state, "a state of 'DCMotorDrive', not of FiveBarPlant")):
        with pytest.raises(FMICallException) as info:
            plant.deserialize_state(data)
        assert info.value.status == 3, "fmi2Error, never fmi2Fatal"
        assert why in plant.messages[-1]
    assert not marker.exists()
    foreign = other.get_state()
    with pytest.raises(FMICallException) as info:
        plant.set_state(foreign)
    assert info.value.status == 3
    assert "issued by another instance" in plant.messages[-1]
    plant.do_step(1e-3, 1e-3)
    own = plant.deserialize_state(plant.serialize_state(plant.get_state()))
    plant.set_state(own)
    plant.free_state(own)
    other.free_state(foreign)
    for inst in (plant, other, drive):
        inst.close()


@pytest.mark.parametrize("shared, refused", [
    ([2.0, [3.0]], False),
    ([[np.array([None], dtype=object)]], True),
    ([{"k": (np.array([None], dtype=object),)}], True),
])
def test_a_reference_where_a_leaf_stands_shares_plain_data_only(shared, refused):
    """Catches a state that makes a number's place share a container holding objects (at any
    depth, in lists, tuples or dicts) being accepted, a plain-data one being refused, or the
    refusal not naming the place, the shared type and what the instance holds."""
    template, tree = {"a": [None], "b": 3.0}, {"a": shared, "b": stateformat.Ref(1)}
    if refused:
        with pytest.raises(fmustate.StateMismatch,
                           match=r"^b: the state shares a list where this instance holds a builtins\.float$"):
            fmustate.apply(template, tree)
    else:
        got = fmustate.apply(template, tree)
        assert got["b"] is got["a"] and got["a"] == [2.0, [3.0]]
