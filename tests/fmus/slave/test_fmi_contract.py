"""The FMI contract of every parcosim slave under careless and hostile calls (issue 13).

Each test checks one row of the table "The FMI calls under hostile use" in
docs/extremes.md, on the slaves called as pythonfmu calls them (in process; the same calls
through fmpy are in tests/fmus/hostile/test_hostile.py).
"""
from __future__ import annotations

import math
import subprocess
import sys
import textwrap
import warnings

import pytest
from pythonfmu import Boolean, Integer, Real, String
from pythonfmu.enums import Fmi2Status

from fmus.export.build import SLAVES
from fmus.slave.base import MIN_STEP, FmiError
from tests.fmus.slave.test_extremes import GOOD, H, make_slave, real_outputs, set_variables, slave_class
from tests.support.paths import ROOT

MODELS = list(SLAVES)


def variables(slave, causality, kind=None):
    return [v for v in slave.vars.values()
            if v.causality is not None and v.causality.name == causality and (kind is None or isinstance(v, kind))]


def stepped(model, parameters=None):
    """An initialised slave that took one good step from t = 0."""
    slave = make_slave(model, parameters)
    set_variables(slave, GOOD[model][1], initialise=False)
    assert slave.do_step(0.0, H), slave.error
    return slave


def setter(slave, v):
    return {Real: slave.set_real, Integer: slave.set_integer, String: slave.set_string,
            Boolean: slave.set_boolean}[type(v)]


def other_value(v, old):
    return {Real: 0.123, Integer: 7, String: "changed", Boolean: not old}[type(v)]


# --- sets ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("model", MODELS)
def test_a_parameter_set_after_initialisation_is_refused_and_keeps_its_value(model):
    """Catches a parameter set after initialisation that changes the model behind the running FMU, a
    refusal that does not name the parameter, value and time, or one that stops the FMU for good."""
    slave = stepped(model)
    parameters = variables(slave, "parameter")
    assert parameters
    for v in parameters:
        old = getattr(slave, v.name)
        value = other_value(v, old)
        with pytest.raises(FmiError) as info:
            setter(slave, v)([v.value_reference], [value])
        message = str(info.value)
        assert v.name in message and repr(value) in message and "after initialisation" in message, message
        assert "t = 0.001" in message, message
        assert getattr(slave, v.name) == old
    assert slave.do_step(H, H), slave.error           # refusing a set does not stop the FMU


@pytest.mark.parametrize("model", MODELS)
def test_a_parameter_set_before_initialisation_is_taken(model):
    """Catches the after-initialisation guard applied too early: parameters set in initialisation mode
    ignored."""
    slave = slave_class(model)(instance_name=model)
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    for v in variables(slave, "parameter", Real)[:3]:
        slave.set_real([v.value_reference], [0.5])
        assert getattr(slave, v.name) == 0.5


@pytest.mark.parametrize("model", MODELS)
def test_an_output_set_is_refused_before_and_after_initialisation(model):
    """Catches an importer able to overwrite an output (the FMU then publishes a value it did not compute),
    before initialisation as well as after."""
    fresh = slave_class(model)(instance_name=model)
    slave = stepped(model)
    for instance in (fresh, slave):
        for v in variables(instance, "output"):
            old = getattr(instance, v.name)
            bad = math.nan if isinstance(v, Real) else other_value(v, old)
            with pytest.raises(FmiError, match=f"{v.name} is an output") as info:
                setter(instance, v)([v.value_reference], [bad])
            assert repr(bad) in str(info.value)
            assert getattr(instance, v.name) == old or (old != old)


def test_a_refused_set_changes_nothing_of_the_same_call():
    """Catches a set call applied value by value up to the refused one: its earlier valid values (i_ref)
    must not be taken either."""
    slave = stepped("DCMotorDrive")
    inputs = {v.name: v.value_reference for v in variables(slave, "input")}
    output = next(v for v in variables(slave, "output") if v.name == "tau")
    before = slave.i_ref
    with pytest.raises(FmiError):
        slave.set_real([inputs["i_ref"], output.value_reference], [5.0, 1.0])
    assert slave.i_ref == before


def test_unknown_and_wrongly_typed_value_references_are_fmi_errors():
    """Catches an unknown value reference read or written as some other variable, or a String read or set
    through the Real/Integer calls, instead of an fmi2Error naming it."""
    slave = stepped("Trajectory")
    with pytest.raises(FmiError, match="value reference 99999 .*is no variable of Trajectory"):
        slave.set_real([99999], [1.0])
    with pytest.raises(FmiError, match="value reference 99999"):
        slave.get_real([99999])
    kind = next(v for v in slave.vars.values() if v.name == "kind")
    with pytest.raises(FmiError, match="kind .* is a String"):
        slave.get_real([kind.value_reference])
    with pytest.raises(FmiError, match="kind .* is a String"):
        slave.set_integer([kind.value_reference], [3])


# --- step sizes ----------------------------------------------------------------------------------

#: Step sizes every FMU refuses.
NEVER = (math.nan, 0.0, -1e-3, math.inf, -math.inf, 1e300, 5e-324, 0.5 * MIN_STEP)
#: (model, h, accepted): what each FMU's model can honour (docs/extremes.md).
STEP_CASES = [
    ("FiveBarPlant", 2.5e-4, True), ("FiveBarPlant", 1e-2, True),
    ("Trajectory", 0.5, True), ("Trajectory", 10.0, True),
    ("Derivator", 5e-4, True), ("Derivator", 3e-4, False), ("Derivator", 2e-3, False),
    ("Derivator", 1e-3 * (1 + 1e-12), True), ("Derivator", 1e-3 / 4 * (1 + 1e-7), False),
    ("PositionController", 5e-4, True), ("PositionController", 3e-4, False), ("PositionController", 0.5, False),
    ("PositionController", 10.0, False), ("BalanceController", 1e-3, True), ("BalanceController", 3e-4, False),
    ("CurrentObserver", 2.5e-4, True), ("CurrentObserver", 3e-4, False), ("CurrentObserver", 0.5, False),
    ("DCMotorDrive", 2.5e-4, True), ("DCMotorDrive", 1e-4, True), ("DCMotorDrive", 3e-4, False),
    ("DCMotorDrive", 2e-3, False),
    ("ActuatedFiveBarPlant", 2.5e-4, True), ("ActuatedFiveBarPlant", 3e-4, False),
]


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("h", NEVER, ids=repr)
def test_absurd_step_sizes_are_refused_naming_h_and_what_is_accepted(model, h):
    """Catches a NaN, zero, negative or huge step size stepped (the outputs change) or refused without
    naming h and what the FMU accepts."""
    slave = make_slave(model)
    set_variables(slave, GOOD[model][1], initialise=False)
    before = real_outputs(slave)
    assert not slave.do_step(0.0, h)
    assert f"step size h = {h!r} s at t = 0.0 s" in slave.error and "accepts" in slave.error, slave.error
    assert real_outputs(slave) == before


@pytest.mark.parametrize("model, h, accepted", STEP_CASES)
def test_each_fmu_accepts_the_steps_its_model_can_honour(model, h, accepted):
    """Catches a sampled FMU that steps with an h its sample time T = 1 ms does not divide, or one that
    refuses the steps it can honour."""
    slave = make_slave(model)
    set_variables(slave, GOOD[model][1], initialise=False)
    ok = slave.do_step(0.0, h)
    assert ok == accepted, slave.error
    if accepted:
        assert all(math.isfinite(v) for v in real_outputs(slave).values())
    else:
        assert f"h = {h!r} s" in slave.error and "sample time T = 0.001 s" in slave.error, slave.error


def test_multi_rate_sub_steps_of_a_drive_follow_each_other():
    """Catches the drive's check of consecutive communication points failing on quarter-millisecond sub-
    steps (rounding of t + h)."""
    slave = make_slave("DCMotorDrive")
    set_variables(slave, GOOD["DCMotorDrive"][1], initialise=False)
    t = 0.0
    for _ in range(12):
        assert slave.do_step(t, 2.5e-4), slave.error
        t += 2.5e-4


# --- communication points ------------------------------------------------------------------------

@pytest.mark.parametrize("model", MODELS)
def test_a_communication_point_that_does_not_follow_the_last_is_refused(model):
    """Catches an FMU that steps again from an earlier time without a state being restored (its state would
    be at 1 ms, the step from 0)."""
    slave = stepped(model)
    assert not slave.do_step(0.0, H)                      # back to the start
    assert "communication point t = 0.0 s does not follow the last one" in slave.error
    assert "t = 0.001 s" in slave.error


def test_the_first_step_starts_at_the_start_time_and_points_may_round():
    """Catches a first step off the start time accepted, or a master's rounded k h refused."""
    slave = make_slave("Trajectory")
    assert not slave.do_step(0.5, H)
    slave = make_slave("Trajectory")
    t = 0.0
    for k in range(1, 2001):                              # master computing k h: rounding differs
        assert slave.do_step(t, H), slave.error
        t = k * H


def test_after_set_state_the_next_point_is_the_states_time():
    """Catches fmi2SetFMUstate that does not restore the expected next communication point (the time the
    state was taken)."""
    slave = stepped("FiveBarPlant")
    state = slave._get_fmu_state()                        # at t = 1 ms
    assert slave.do_step(H, H) and slave.do_step(2 * H, H)
    slave._set_fmu_state(state)
    assert not slave.do_step(3 * H, H)                    # the state's time is 1 ms
    slave._set_fmu_state(state)
    assert slave.do_step(H, H), slave.error


# --- the call order ------------------------------------------------------------------------------

def test_do_step_after_terminate_is_refused():
    """Catches an FMU that keeps stepping after fmi2Terminate."""
    slave = stepped("Derivator")
    slave.terminate()
    assert not slave.do_step(H, H)
    assert "after fmi2Terminate" in slave.error


def test_a_refusal_before_initialisation_is_cleared_by_a_good_initialisation():
    """Catches an error left over from a doStep called before initialisation that poisons the FMU after a
    good initialisation."""
    slave = slave_class("Trajectory")(instance_name="t")
    slave.setup_experiment(0.0, None, None)
    assert not slave.do_step(0.0, H)
    assert "before initialisation" in slave.error
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    assert slave.error == ""
    assert slave.do_step(0.0, H), slave.error


def test_after_a_refused_step_every_step_is_refused_until_a_state_is_restored():
    """Catches an FMU that steps on after a refused step (FMI 2.0 stepFailed), that overwrites the
    refusal's cause, or that stays refused after a state from before is restored."""
    slave = stepped("Derivator")
    state = slave._get_fmu_state()
    assert not slave.do_step(H, 2 * H)
    first = slave.error
    assert not slave.do_step(H, H)                        # sane, but refused: FMI 2.0 stepFailed
    assert slave.error == first                           # ``error`` keeps the cause
    slave._set_fmu_state(state)
    assert slave.do_step(H, H), slave.error
    assert slave.error == ""


# --- values that used to give NaN or unnamed messages -----------------------------------------

@pytest.mark.parametrize("model, parameters, name", [
    ("Derivator", {"fc_vel": 1e-300}, "fc_vel"),
    ("Derivator", {"fc_acc": 1e-300}, "fc_acc"),
    ("Derivator", {"fc_vel": 5e-324}, "fc_vel"),
    ("Derivator", {"fc_acc": 5e-324}, "fc_acc"),
    ("Derivator", {"T": 5e-324}, "T"),
    ("CurrentObserver", {"R": 5e-324}, "R"),
    ("DCMotorDrive", {"R": 5e-324}, "R"),
    ("DCMotorDrive", {"T": 5e-324}, "T"),
    ("ActuatedFiveBarPlant", {"L1": 0.0}, "L1"),
    ("ActuatedFiveBarPlant", {"L2": 0.0}, "L2"),
    ("PositionController", {"T": 5e-324}, "T"),
])
def test_tiny_parameters_are_refused_at_initialisation_naming_them(model, parameters, name):
    """Catches a denormal or zero parameter the model divides by accepted at initialisation (inf or NaN
    later), or refused without its name and value."""
    slave = make_slave(model, parameters)
    assert not slave._ready
    value = parameters[name]
    assert f"parameter {name} = {value!r}" in slave.error and "(t = 0 s)" in slave.error, slave.error
    assert not slave.do_step(0.0, H)


@pytest.mark.parametrize("value", [1.7976931348623157e308, -1.7976931348623157e308])
def test_derivator_refuses_dbl_max_naming_the_input(value):
    """Catches the derivator's difference quotient overflowing on a finite but huge input, or a refusal
    that changes the outputs."""
    slave = stepped("Derivator")
    before = real_outputs(slave)
    slave.q1 = value
    assert not slave.do_step(H, H)
    assert f"input q1 = {value!r}" in slave.error and "t = 0.001 s" in slave.error
    assert real_outputs(slave) == before


def test_a_plant_step_that_would_take_over_the_limit_is_refused_at_initialisation():
    """Counted, not timed (fmus/slave/budget.py; tests/fmus/slave/test_call_limits.py covers every plant)."""
    slave = make_slave("FiveBarPlant", {"kernel": "general", "substeps": 10000})
    assert "kernel = 'general', substeps = 10000" in slave.error and "use substeps <=" in slave.error
    assert "needs 40000 right-hand-side evaluations" in slave.error
    ok = make_slave("FiveBarPlant", {"kernel": "general", "substeps": 10})
    assert ok._ready, ok.error


# --- resources -----------------------------------------------------------------------------------

def test_instances_do_not_grow_sys_path():
    """Catches a slave that appends to sys.path on every instantiation (pythonfmu's wrapper does)."""
    sys.path.append(sys.path[0])                           # what pythonfmu's wrapper does each time
    sys.path.append(sys.path[0])
    for _ in range(3):
        slave_class("Trajectory")(instance_name="t")
    assert len(sys.path) == len(set(sys.path))


def test_two_controllers_initialised_from_two_threads_both_work(tmp_path):
    """In a fresh interpreter, where the law is not compiled yet."""
    code = textwrap.dedent("""
        import threading
        from tests.fmus.slave.test_extremes import make_slave
        slaves = [None, None]
        def init(k):
            slaves[k] = make_slave("PositionController")
        threads = [threading.Thread(target=init, args=(k,)) for k in range(2)]
        for t in threads: t.start()
        for t in threads: t.join()
        print([s.error for s in slaves])
        assert all(s._ready for s in slaves), [s.error for s in slaves]
    """)
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300,
                         env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    assert run.returncode == 0, run.stderr[-2000:]


def _table(cache_dir, monkeypatch):
    from controller.model import TabulatedModel
    from plant import get_preset

    monkeypatch.setenv("PARCOSIM_CACHE", str(cache_dir))
    return TabulatedModel(get_preset("bench"), step=0.02)


def test_a_corrupt_table_cache_is_rebuilt_with_a_warning_naming_it(tmp_path, monkeypatch):
    """Catches a corrupt controller table cache that is loaded (or crashes the load) instead of being
    rebuilt to the same table."""
    good = _table(tmp_path, monkeypatch)
    (cache,) = tmp_path.glob("model_*.npz")
    cache.write_bytes(b"not a table")
    with pytest.warns(UserWarning, match=f"{cache}.*unreadable"):
        again = _table(tmp_path, monkeypatch)
    assert (again.table[~(again.table != again.table)] == good.table[~(good.table != good.table)]).all()


def test_an_unwritable_table_cache_keeps_the_table_in_memory(tmp_path, monkeypatch):
    """Catches an unwritable cache directory that fails the table's construction instead of keeping it in
    memory."""
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache directory should be")
    with pytest.warns(UserWarning, match="cannot be written.*stays in memory"):
        model = _table(blocker / "cache", monkeypatch)
    assert model.table.size > 0


def test_a_controller_with_an_unwritable_cache_initialises(tmp_path, monkeypatch):
    """Catches the PositionController FMU refusing its initialisation when its table cache cannot be
    written."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("PARCOSIM_CACHE", str(blocker / "cache"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        slave = make_slave("PositionController", {"grid_step": 0.02})
    assert slave._ready, slave.error


def test_a_tunable_parameter_may_be_set_after_initialisation():
    """Catches the after-initialisation guard refusing a parameter declared tunable."""
    from pythonfmu import Fmi2Variability

    from fmus.slave.base import GuardedSlave

    class Tunable(GuardedSlave):
        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.declare("gain", "parameter", 1.0, "a tunable gain", variability=Fmi2Variability.tunable)
            self.declare("fixed", "parameter", 1.0, "a fixed one")

        def step(self, current_time, step_size):
            pass

    slave = Tunable(instance_name="t")
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    slave.set_real([vr["gain"]], [2.0])
    assert slave.gain == 2.0
    with pytest.raises(FmiError, match="parameter fixed = 2.0 refused after initialisation"):
        slave.set_real([vr["fixed"]], [2.0])


# --- outputs in Initialization Mode ----------------------------------------------------------------

def _initializing(model, parameters=None):
    """A slave in Initialization Mode with GOOD's parameters (and ``parameters``) set."""
    slave = slave_class(model)(instance_name=model)
    slave.setup_experiment(0.0, None, None)
    slave.enter_initialization_mode()
    set_variables(slave, {**GOOD[model][0], **(parameters or {})}, initialise=False)
    return slave


def _outputs(slave):
    """Every output but ``error``, read through the FMI getters (name -> value)."""
    out = {}
    for kind, get in ((Real, slave.get_real), (Integer, slave.get_integer), (Boolean, slave.get_boolean),
                      (String, slave.get_string)):
        chosen = [v for v in variables(slave, "output", kind) if v.name != "error"]
        out.update(zip((v.name for v in chosen), get([v.value_reference for v in chosen])))
    return out


@pytest.mark.parametrize("model", MODELS)
def test_outputs_read_in_initialization_mode_are_those_it_starts_from(model, monkeypatch):
    """FMI 2.0 (4.2.4): an output (initial="calculated") may be read in Initialization Mode and is
    then calculated from what was set so far.  Read there, every output equals what the slave
    publishes after fmi2ExitInitializationMode, which does not build the model a second time."""
    slave = _initializing(model)
    builds = []
    setup = type(slave).setup
    monkeypatch.setattr(type(slave), "setup", lambda self: (builds.append(model), setup(self))[1])
    during = _outputs(slave)
    slave.exit_initialization_mode()
    assert slave.error == "" and builds == [model]
    assert _outputs(slave) == during


def test_outputs_in_initialization_mode_follow_the_parameters_set_after_a_read():
    """Before the fix the plant read (0, 0), a pose it cannot take; a parameter set after a read
    is taken by the next read (the trajectory's hold point) and by the initialisation."""
    plant = _initializing("FiveBarPlant")
    x, y = _outputs(plant)["x"], _outputs(plant)["y"]
    assert (x, y) == (plant.x0, plant.y0) and (x, y) != (0.0, 0.0)
    traj = _initializing("Trajectory", {"kind": "hold"})
    assert (_outputs(traj)["x_d"], _outputs(traj)["y_d"]) == (-0.002, 0.108)
    set_variables(traj, {"x_hold": 0.01, "y_hold": 0.2}, initialise=False)
    assert (_outputs(traj)["x_d"], _outputs(traj)["y_d"]) == (0.01, 0.2)
    traj.exit_initialization_mode()
    assert (_outputs(traj)["x_d"], _outputs(traj)["y_d"], _outputs(traj)["x_start"]) == (0.01, 0.2, 0.01)


def test_a_read_in_initialization_mode_with_a_bad_parameter_keeps_the_start_values_and_warns_once():
    """A parameter the model refuses: the read is not an error (libcosim aborts on one while it
    initialises): the outputs keep their start values, a warning names the parameter once for
    repeated reads, and the initialisation is refused with it as without the read.  Mended, the
    read gives the calculated values and the initialisation goes on."""
    traj = _initializing("Trajectory", {"kind": "triangle", "side_time": -0.5})
    logged = []
    traj.log = lambda message, status, category: logged.append((message, status, category))
    x_d = next(v.value_reference for v in traj.vars.values() if v.name == "x_d")
    assert traj.get_real([x_d]) == traj.get_real([x_d]) == [0.0]
    assert logged == [("Trajectory: the outputs read in Initialization Mode keep their start values: parameter "
                       "side_time = -0.5 s must be > 0; fmi2ExitInitializationMode will refuse the initialisation",
                       Fmi2Status.warning, "logStatusWarning")]
    set_variables(traj, {"side_time": 0.5}, initialise=False)
    assert traj.get_real([x_d]) == [-0.002]
    traj.exit_initialization_mode()
    assert traj.error == "" and traj.do_step(0.0, H)
    refused = _initializing("Trajectory", {"kind": "triangle", "side_time": -0.5})
    refused.get_real([x_d])
    refused.exit_initialization_mode()
    assert refused.error.startswith("initialisation refused: parameter side_time = -0.5 s must be > 0")
    assert not refused.do_step(0.0, H)


def test_after_a_read_an_input_set_rebuilds_at_initialisation_and_a_parameter_set_at_the_next_read(monkeypatch):
    """The initial outputs follow from parameters: an input set after a read does not rebuild
    the model for the next read, but initialisation builds again with it; a parameter set does
    make the next read rebuild."""
    plant = _initializing("FiveBarPlant")
    builds = []
    setup = type(plant).setup
    monkeypatch.setattr(type(plant), "setup", lambda self: (builds.append(1), setup(self))[1])
    _outputs(plant)
    set_variables(plant, {"tau1": 0.01}, initialise=False)
    _outputs(plant)
    assert len(builds) == 1
    set_variables(plant, {"x0": 0.0}, initialise=False)
    assert _outputs(plant)["x"] == 0.0 and len(builds) == 2
    set_variables(plant, {"tau2": 0.02}, initialise=False)
    plant.exit_initialization_mode()
    assert len(builds) == 3 and plant.error == ""
