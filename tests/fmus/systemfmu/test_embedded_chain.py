"""A system inside one FMU, in process (fmus/systemfmu): what its build writes read back (the
system, the role, the plant's name and the step-size flag), the chain's refusal when its model
of the plant cannot follow a measurement, and the step sizes its slaves refuse and why: a
ControlChain refuses any step but h as such whatever the work limit, a ClosedLoop takes whole
multiples of h up to the work limit and names the most it takes (issue 31: seed 3601's
survivors [103], [251] and [276]).  No FMU is built: fast."""
from __future__ import annotations

import json
import math

import pytest

from fmus.cosim.backends import CoSimulationError
from fmus.slave import budget
from fmus.systemfmu import export
from fmus.systemfmu.cores import SYSTEM_FILE, ChainCore, system_from_dict
from scenarios.packaging.chain import package_scene
from scenarios.scenes.catalogue import get_scene
from tests.fmus.slave.test_parameter_extremes import new_system_slave

SCENE = "thesis_sim_circle"


@pytest.fixture(scope="module")
def chain_system():
    return package_scene(get_scene(SCENE)).chain


@pytest.mark.parametrize("role, variable", [("loop", "true"), ("chain", "false")])
def test_the_build_writes_the_system_role_and_plant_and_the_step_flag_of_the_role(monkeypatch, chain_system, role,
                                                                                   variable):
    """The slave's module and class, ``system.json`` (read back: the same System, role and
    plant) and canHandleVariableCommunicationStepSize: "true" for the loop (it takes any whole
    number of its steps), "false" for the chain (exactly one).  Catches the flag decided on
    another variable (seed 3601's [251]: ``plant == "loop"``, "false" for both) or the spec
    written incompletely."""
    built = {}

    def build_bundled_fmu(script, model, path, resources=(), **options):
        built.update(script=script.name, model=model, path=path, options=options,
                     spec=json.loads(next(r for r in resources if r.name == SYSTEM_FILE).read_text()))
        return path
    monkeypatch.setattr(export, "build_bundled_fmu", build_bundled_fmu)
    system = chain_system if role == "chain" else export.closed_loop_system(get_scene(SCENE).system)
    assert export.build_system_fmu(role, system, "/nowhere/Sys.fmu", plant="plant") == export.Path("/nowhere/Sys.fmu")
    module, model = export.ROLES[role]
    assert (built["script"], built["model"]) == (f"{module}.py", model)
    assert built["options"] == {"canHandleVariableCommunicationStepSize": variable, **export.STATE_OPTIONS}
    assert (built["spec"]["role"], built["spec"]["plant"]) == (role, "plant")
    assert system_from_dict(built["spec"]["system"]) == system


def test_a_measurement_the_model_cannot_follow_is_the_plants_refusal_at_the_steps_time(chain_system):
    """Measured angles (0, pi) put the elbows 0.34 m apart: no assembly.  The chain's step from
    t = h refuses as the plant's (instance ``plant``, time h), naming the measurement and the
    model's reason.  Catches the error's instance and time swapped (seed 3601's [276]: the
    message then fails to format and a ValueError escapes) or the reason lost."""
    chain = ChainCore(chain_system, "plant")
    chain.initialize()
    h = chain_system.step
    chain.step(0.0, h, {"q1": 0.5, "q2": 2.6, "dq1": 0.0, "dq2": 0.0})
    measured = {"q1": 0.0, "q2": math.pi, "dq1": 0.0, "dq2": 0.0}
    with pytest.raises(CoSimulationError) as refused:
        chain.step(h, h, measured)
    error = refused.value
    assert (error.instance, error.time) == ("plant", h)
    assert error.message.startswith(f"the plant model cannot follow the measurement {measured}: no assembly for "
                                    "q1=0, q2=3.14159 rad")
    assert str(error) == f"plant refused the step from t = {h:.6g} s: {error.message}"


def _initialised(model: str):
    slave = new_system_slave(model)
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    assert slave.error == ""
    return slave


def test_a_chain_refuses_two_steps_as_a_step_size_it_never_takes_even_past_the_work_limit(monkeypatch):
    """The work limit made 1.5 of the chain's steps: one step h is taken; 2 h is refused
    because the chain takes exactly h, not because two steps would pass the limit.  Catches
    the rule "more than one step needs takes_multiples" loosened (seed 3601's [103]: 2 steps let
    through to the work limit, whose refusal then names a limit instead)."""
    slave = _initialised("ControlChain")
    h = slave.system.step
    _, seconds = slave.core.work_per_step()
    monkeypatch.setattr(budget, "CALL_CPU_SECONDS", 1.5 * seconds)
    assert slave.do_step(0.0, h), slave.error
    assert not slave.do_step(h, 2 * h)
    assert slave.error.startswith(f"step size {2 * h!r} s at t = {h:.6g} s: this FMU steps its system at its "
                                  f"communication step; the step size must be h = {h!r} s")


def test_a_loop_takes_whole_multiples_up_to_the_work_limit_and_names_the_most(monkeypatch):
    """The work limit made 3.5 of the loop's steps: 3 h is taken, 4 h refused before any step
    is taken, naming the step and the most it takes (3 steps, 3 h).  Catches the limit's count
    (steps times component steps) or its advice computed otherwise."""
    slave = _initialised("ClosedLoop")
    h = slave.system.step
    count, seconds = slave.core.work_per_step()
    monkeypatch.setattr(budget, "CALL_CPU_SECONDS", 3.5 * seconds)
    assert slave.do_step(0.0, 3 * h), slave.error
    time_before = slave.core.stepper.time
    assert not slave.do_step(3 * h, 4 * h)
    assert slave.core.stepper.time == time_before
    assert f"step size h = {4 * h!r} s at t = {3 * h!r} s" in slave.error
    assert f"4 of its steps h = {h!r} s, {count} component steps each; take steps of at most {3 * h:.6g} s " \
           "(3 of its steps)" in slave.error


def test_the_chain_counts_its_corrected_steps_from_zero_and_its_state_keeps_the_count(chain_system):
    """No correction at initialisation nor at the first step (whatever is measured there);
    each later step whose measurement is 10 mrad off the model's angle counts one; a state
    taken and restored brings the count back.  Catches the count started at another value,
    the first step corrected, a correction not counted, and the count not in the state."""
    chain = ChainCore(chain_system, "plant")
    assert chain.corrections == 0
    chain.initialize()
    h = chain_system.step
    chain.step(0.0, h, {"q1": 0.3, "q2": 2.0, "dq1": 1.0, "dq2": -1.0})
    assert chain.corrections == 0
    slave = chain.model.slave
    for k in range(1, 4):
        off = {"q1": slave.q1 + 0.01, "q2": slave.q2, "dq1": slave.dq1, "dq2": slave.dq2}
        chain.step(k * h, h, off)
        assert chain.corrections == k
    state = chain.state()
    chain.step(4 * h, h, {"q1": slave.q1 + 0.01, "q2": slave.q2, "dq1": slave.dq1, "dq2": slave.dq2})
    assert chain.corrections == 4
    chain.restore(state)
    assert chain.corrections == 3
