"""Extreme values at every parameter of every FMU (issue 30, item 5; docs/extremes.md).

One parameter at a time is set to an extreme value of its type (the others as in a good
run); the FMU is initialised and takes a few steps.  Either the value is accepted and the
outputs stay finite over those steps, or the FMU refuses (at initialisation or at a later
step) with a message that names the parameter, the value and the time.

The rule a message must follow (:func:`naming_problem`): it holds the time of the refused
call as ``t = <number> s`` (the number within 1e-5 of the time), and, with those time
clauses taken out, the value as set, spelled as Python's ``repr`` spells it (``5e-324``,
``-0.0``, ``nan``, ``-2147483648``, ``''``, ``'no_such_name'``) as a whole token, and the
parameter's name (``lam``; in a system FMU, whose parameter is ``ctrl.lam``, the component's
own ``lam``) where it names a value: ``lam = ...``, ``lam: ...``, ``(lam) = ...``, ``lam must
...``, ``|lam|``, ``parameter lam`` (not ``preset`` in "unknown preset 'x'").  A system FMU
says which component refused in its record (``refusal``): the instance ``<FMU>.<component>``.

In process: every parameter of every atomic FMU at every value of its type, in several
configurations (so that a parameter only one branch of a model uses is exercised); the system
FMUs for a sample (each case builds and initialises a whole scene).  Through the built FMUs
and fmpy: every parameter of one FMU of each kind at two values, and a sample of the
ControlChain's; the same outcome and message as in process, a refusal fmi2Discard or
fmi2Error, never fmi2Fatal.
"""
from __future__ import annotations

import atexit
import json
import math
import re
import shutil
import sys
import tempfile
from functools import lru_cache

import pytest
from fmpy.fmi1 import FMICallException
from pythonfmu import Boolean, Integer, Real, String

from fmus.status import RunError
from fmus.systemfmu.cores import SYSTEM_FILE, system_to_dict
from fmus.slave.registry import SLAVES
from tests.support.fmi_support import FmuInstance
from tests.fmus.slave.test_extremes import GOOD, slave_class

pytestmark = [pytest.mark.sweep]

H = 1e-3
#: Start time: where importers start, and where the models evaluate their first sample (a
#: triangle of side_time 1e-200 s divided by zero at t = 0 only).  The time a step's refusal
#: names is k h.
T0 = 0.0
#: Steps after initialisation.
STEPS = 3

#: Extreme values per FMI type: Reals the non-finite ones, signed zeros, the smallest
#: subnormals, a tiny and huge magnitudes and the largest double; Integers the edges of
#: fmi2Integer (int32); Strings empty and unknown; Booleans both.
EXTREMES = {
    Real: (math.nan, math.inf, -math.inf, 0.0, -0.0, 5e-324, -5e-324, 1e-200, 1e300, -1e300, sys.float_info.max),
    Integer: (0, -1, 2 ** 31 - 1, -2 ** 31),
    String: ("", "no_such_name"),
    Boolean: (False, True),
}

#: Configurations (parameters beyond the good run's) every parameter of an atomic FMU is tried
#: in: one per branch of the model that uses parameters (or uses them otherwise) where the
#: default does not.
CONFIGURATIONS = {
    "FiveBarPlant": ({}, {"method": "dopri5"}, {"kernel": "general"}),
    "DCMotorDrive": ({}, {"mode": "voltage", "method": "euler"}, {"friction": "lugre"}),
    "CurrentObserver": ({}, {"kind": "dynamic"}),
    "Trajectory": ({"kind": "circle"}, {"kind": "triangle"}, {"kind": "hold"}, {"kind": "thesis_circle"}),
    "Derivator": ({}, {"start_from_input": False}),
    "PositionController": ({}, {"strategy": "PDMDq"}, {"strategy": "SMCx"}, {"model": "exact"}),
    "ActuatedFiveBarPlant": ({}, {"mode": "voltage"}),
    "WheeledPendulum": ({}, {"model": "seed", "yaw": False}),
    "BalanceController": ({}, {"electrics": "ideal", "route": "forward_turn"}),
    "SpecPlant": ({},),
}
#: Configurations tried for the parameters they concern only: SpecPlant's general kernel takes
#: about 3 ms a right-hand side, and dopri5 uses its tolerances alone.
NARROW_CONFIGURATIONS = {"SpecPlant": (({"method": "dopri5"}, ("rtol", "atol")),)}
#: The spec of the in-process SpecPlant.
SPEC = "bench_5r"


def configurations(model: str, name: str) -> list:
    """The configurations parameter ``name`` of ``model`` is tried in."""
    narrow = [c for c, names in NARROW_CONFIGURATIONS.get(model, ()) if name in names]
    return [*CONFIGURATIONS[model], *narrow]


# --- the rule a refusal's message follows --------------------------------------------------

_TIME = re.compile(r"(?<![\w.])t = (-?\d+(?:\.\d*)?(?:e[+-]?\d+)?) s\b")


def _token(text: str) -> re.Pattern:
    """``text`` as a whole token: no name character or number part glued to either side."""
    return re.compile(rf"(?<![\w.+-]){re.escape(text)}(?![\w]|\.\d)")


def _naming(name: str) -> re.Pattern:
    """``name`` where it names a value (module docstring)."""
    token = rf"(?<![\w.]){re.escape(name)}(?![\w.])"
    return re.compile(rf"{token}(?=\s*[=:]|\)\s*=|\s+must\b|\|)|(?<=parameter ){token}|(?<=parameters ){token}")


def naming_problem(message: str, name: str, value, time: float) -> str | None:
    """What ``message`` fails to name of (parameter ``name`` = ``value`` at ``time``), or None."""
    times = [float(t) for t in _TIME.findall(message)]
    if not any(math.isclose(t, time, rel_tol=1e-5, abs_tol=1e-12) for t in times):
        return f"no time t = {time:g} s (times named: {times})"
    rest = _TIME.sub("", message)
    if not _naming(name).search(rest):
        return f"no parameter {name}"
    if not _token(repr(value)).search(rest):
        return f"no value {value!r}"
    return None


def test_the_rule_catches_a_message_that_misses_a_part():
    """The rule itself: each missing part is caught; a value glued to another number, the
    time's number and a name used as a word are not the parts."""
    good = "initialisation refused: parameter R = 5e-324 is absurdly small (t = 0.25 s)"
    assert naming_problem(good, "R", 5e-324, 0.25) is None
    assert naming_problem("initialisation refused: division by zero (t = 0.25 s)", "R", 5e-324, 0.25)
    assert naming_problem(good, "R", 5e-324, 0.0).startswith("no time")
    assert naming_problem(good, "L", 5e-324, 0.25) == "no parameter L"
    assert naming_problem(good.replace("5e-324", "4.94066e-324"), "R", 5e-324, 0.25) == "no value 5e-324"
    assert naming_problem("R = -0.0 refused (t = 0 s)", "R", 0.0, 0.0) == "no value 0.0"
    assert naming_problem("unknown preset 'a' (t = 0 s)", "preset", "a", 0.0) == "no parameter preset"
    assert naming_problem("plant.x0 = nan (t = 0 s)", "x0", math.nan, 0.0) == "no parameter x0"
    assert naming_problem("plant.x0 = nan (t = 0 s)", "plant.x0", math.nan, 0.0) is None


# --- one case: set, initialise, step ---------------------------------------------------------

def _set(slave, values: dict) -> None:
    """Set ``values`` (name -> value) through the slave's FMI setters, as an importer does."""
    by_name = {v.name: v for v in slave.vars.values()}
    setters = {Real: slave.set_real, Integer: slave.set_integer, String: slave.set_string,
               Boolean: slave.set_boolean}
    for name, value in values.items():
        v = by_name[name]
        setters[type(v)]([v.value_reference], [value])


def _numeric_outputs(slave) -> list:
    """The names of the slave's Real and Integer outputs."""
    return [v.name for v in slave.vars.values()
            if isinstance(v, (Real, Integer)) and v.causality is not None and v.causality.name == "output"]


def run_case(slave, parameters: dict, inputs: dict, name: str, value, t0: float):
    """Initialise ``slave`` with ``parameters`` and ``name`` = ``value``, then take
    :data:`STEPS` steps with ``inputs``.

    Returns
    -------
    (outcome, message, time) : tuple
        outcome "accepted", "refused at initialisation" or "refused at a step"; the message
        of the refusal (the String output ``error``) and the time of the refused call.

    Raises
    ------
    AssertionError
        An output is not finite after a step the FMU accepted (NaN with fmi2OK).
    """
    slave.setup_experiment(t0, None, None)
    slave.enter_initialization_mode()
    _set(slave, {**parameters, name: value})
    slave.exit_initialization_mode()
    if slave.error:
        return "refused at initialisation", slave.error, t0
    outputs = _numeric_outputs(slave)
    for k in range(STEPS):
        t = t0 + k * H
        _set(slave, inputs)
        if not slave.do_step(t, H):
            return "refused at a step", slave.error, t
        values = {n: getattr(slave, n) for n in outputs}
        assert all(math.isfinite(v) for v in values.values()), f"{name} = {value!r}: accepted step at t = {t}: {values}"
    return "accepted", "", None


def check(slave, parameters, inputs, name, value, t0) -> list:
    """:func:`run_case`; the problems of its refusal: the message (:func:`naming_problem`, a
    system FMU's component's parameter by its own name) and, in a system FMU, the record's
    instance, which must be the component's (``<FMU>.<component>``)."""
    outcome, message, time = run_case(slave, parameters, inputs, name, value, t0)
    if outcome == "accepted":
        return []
    component, _, parameter = name.rpartition(".")
    problem = naming_problem(message, parameter, value, time)
    if problem is None and component:
        instance = RunError.from_json(slave.refusal).instance
        if instance != f"{slave.instance_name}.{component}":
            problem = f"the record's instance is {instance!r}"
    return [f"{name} = {value!r} ({outcome}): {problem}: {message!r}"] if problem else []


# --- the atomic FMUs ---------------------------------------------------------------------------

@lru_cache(maxsize=None)
def _spec_resources() -> str:
    """A resources folder holding the spec :data:`SPEC` (what ``build-plant`` bundles)."""
    from fmus.slaves.parcosim_specplant import SPEC_RESOURCE
    from plant.spec import load, spec_path

    folder = tempfile.mkdtemp(prefix="parcosim_spec_resources_")
    atexit.register(shutil.rmtree, folder, ignore_errors=True)      # nothing left in the temp folder
    with open(f"{folder}/{SPEC_RESOURCE}", "w", encoding="utf-8") as f:
        f.write(load(spec_path(SPEC)).text)
    return folder


def new_slave(model: str):
    """A fresh slave of the atomic FMU ``model``, as pythonfmu makes it."""
    if model == "SpecPlant":
        from fmus.slaves.parcosim_specplant import SpecPlant

        return SpecPlant(instance_name=model, resources=_spec_resources())
    return slave_class(model)(instance_name=model)


GOOD_RUNS = {**GOOD, "SpecPlant": ({}, {"tau1": 0.01, "tau2": -0.01})}


def _parameters(slave) -> list:
    """The slave's parameters: (name, FMI type)."""
    return [(v.name, type(v)) for v in slave.vars.values()
            if v.causality is not None and v.causality.name == "parameter"]


def _atomic_cases():
    return [pytest.param(model, name, kind, id=f"{model}.{name}")
            for model in (*SLAVES, "SpecPlant") for name, kind in _parameters(new_slave(model))]


@pytest.mark.parametrize("model, name, kind", _atomic_cases())
def test_every_refusal_of_an_extreme_parameter_names_it_the_value_and_the_time(model, name, kind):
    parameters, inputs = GOOD_RUNS[model]
    problems = []
    for configuration in configurations(model, name):
        for value in EXTREMES[kind]:
            found = check(new_slave(model), {**parameters, **configuration}, inputs, name, value, T0)
            problems += [f"{configuration}: {problem}" for problem in found]
    assert not problems, "\n".join(problems)


# --- the system FMUs: every inner parameter is a parameter <instance>.<name> -----------------

#: The scene inside the system FMUs (tests/fmus/slave/test_fmu_state.py's ``system_fmus``).
SCENE = "bench_circle_TCMDx"
#: The values the plant's parameters of the ControlChain are tried at (issue 30: "ControlChain
#: with a bad plant parameter"); each case initialises a whole scene (about 0.1 s).
CHAIN_PLANT_EXTREMES = {Real: (math.nan, 5e-324, -1e300), Integer: (-2 ** 31,), String: ("no_such_name",),
                        Boolean: (False, True)}
#: One value of each type the components refuse, or the other Boolean.
REFUSED = {Real: math.nan, Integer: -2 ** 31, String: "no_such_name"}


@lru_cache(maxsize=None)
def _system(model: str):
    """(slave class, resources folder, measured inputs) of the system FMU ``model`` of
    :data:`SCENE`, its ``system.json`` as :func:`fmus.systemfmu.export.build_system_fmu` writes it."""
    from fmus.cosim.backends import InProcessInstance
    from fmus.slaves.parcosim_closedloop import ClosedLoop
    from fmus.slaves.parcosim_controlchain import ControlChain
    from scenarios.packaging.chain import PLANT, package_scene
    from scenarios.scenes.catalogue import get_scene

    scene = get_scene(SCENE)
    if model == "ClosedLoop":
        role, system, cls = "loop", scene.system, ClosedLoop
        assert {"plant.x", "plant.y"} <= set(system.record)     # the FMU's outputs x, y
    else:
        role, system, cls = "chain", package_scene(scene).chain, ControlChain
    folder = tempfile.mkdtemp(prefix=f"parcosim_{role}_resources_")
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    with open(f"{folder}/{SYSTEM_FILE}", "w", encoding="utf-8") as f:
        json.dump({"role": role, "plant": PLANT, "system": system_to_dict(system)}, f)
    plant = InProcessInstance(system.component(PLANT).model, PLANT)
    plant.initialize(system.component(PLANT).parameters, 0.0)
    measured = {v.name: getattr(plant.slave, v.name) for v in cls(instance_name="scan", resources=folder).vars.values()
                if v.causality is not None and v.causality.name == "input"}
    return cls, folder, measured


def new_system_slave(model: str):
    cls, folder, _ = _system(model)
    return cls(instance_name=model, resources=folder)


def _system_sample(model: str) -> list:
    """(name, value): the first parameter of each type of every component at the value of
    :data:`REFUSED` (or both Booleans); for the ControlChain every parameter of its plant (the
    model it predicts the real plant by) at :data:`CHAIN_PLANT_EXTREMES`; and ``deriv.T`` at
    1.5 ms, refused at the first step (the step size must divide it), not at initialisation."""
    sample, seen = [], set()
    for name, kind in _parameters(new_system_slave(model)):
        component = name.split(".")[0]
        if model == "ControlChain" and component == "plant":
            sample += [(name, value) for value in CHAIN_PLANT_EXTREMES[kind]]
        elif (component, kind) not in seen:
            seen.add((component, kind))
            sample += [(name, REFUSED[kind])] if kind in REFUSED else [(name, False), (name, True)]
    return [*sample, ("deriv.T", 1.5e-3)]


def _system_cases():
    return [pytest.param(model, name, value, id=f"{model}.{name}={value!r}")
            for model in ("ClosedLoop", "ControlChain") for name, value in _system_sample(model)]


@pytest.mark.parametrize("model, name, value", _system_cases())
def test_a_system_fmu_refusal_names_the_inner_parameter_and_its_component_in_the_record(model, name, value):
    _, _, measured = _system(model)
    problems = check(new_system_slave(model), {}, measured, name, value, 0.0)
    assert not problems, "\n".join(problems)


# --- the same through the built FMUs (fmpy) ----------------------------------------------------

#: Two values per type through fmpy: one every parameter refuses, one some accept.
FMPY_VALUES = {Real: (math.nan, 5e-324), Integer: (-2 ** 31, 2 ** 31 - 1), String: ("", "no_such_name"),
               Boolean: (False, True)}
#: One FMU of each kind, every parameter: a plant, a drive, a sampled component, a source.
FMPY_MODELS = ("FiveBarPlant", "DCMotorDrive", "Derivator", "Trajectory")


def run_through_fmpy(path, parameters: dict, inputs: dict, name: str, value):
    """:func:`run_case` through the FMU at ``path`` (fmpy, start time 0); a refused call must
    return fmi2Discard or fmi2Error, never fmi2Fatal."""
    fmu = FmuInstance(path, {**parameters, name: value}, initialise=False)
    try:
        try:
            fmu.initialise()
        except FMICallException as exc:
            assert exc.status in (2, 3), f"{name} = {value!r}: fmi2ExitInitializationMode returned {exc.status}"
            return "refused at initialisation", fmu.get("error"), 0.0
        if fmu.get("error"):
            return "refused at initialisation", fmu.get("error"), 0.0
        outputs = [v.name for v in fmu.md.modelVariables
                   if v.causality == "output" and v.type in ("Real", "Integer")]
        for k in range(STEPS):
            try:
                fmu.step(H, **inputs)
            except FMICallException as exc:
                assert exc.status in (2, 3), f"{name} = {value!r}: fmi2DoStep returned {exc.status}"
                return "refused at a step", fmu.get("error"), k * H
            values = {n: fmu.get(n) for n in outputs}
            assert all(math.isfinite(v) for v in values.values()), f"{name} = {value!r}: step {k}: {values}"
        return "accepted", "", None
    finally:
        fmu.close()


def _fmpy_cases():
    cases = [pytest.param(model, name, value, id=f"{model}.{name}={value!r}")
             for model in FMPY_MODELS for name, kind in _parameters(new_slave(model)) for value in FMPY_VALUES[kind]]
    return cases + [pytest.param("ControlChain", name, value, id=f"ControlChain.{name}={value!r}")
                    for name, value in _system_sample("ControlChain")
                    if not name.startswith("plant.") or name == "plant.x0"]


@pytest.fixture(scope="module")
def chain_fmu(tmp_path_factory):
    """The ControlChain FMU of :data:`SCENE`'s package."""
    from fmus.systemfmu.export import build_system_fmu
    from scenarios.packaging.chain import PLANT, package_scene
    from scenarios.scenes.catalogue import get_scene

    return build_system_fmu("chain", package_scene(get_scene(SCENE)).chain,
                            tmp_path_factory.mktemp("chain") / "chain.fmu", PLANT)


@pytest.mark.parametrize("model, name, value", _fmpy_cases())
def test_through_fmpy_the_refusal_is_the_in_process_one_and_never_fatal(built_fmus, chain_fmu, model, name, value):
    if model == "ControlChain":
        path, parameters, inputs = chain_fmu, {}, _system(model)[2]
        slave = new_system_slave(model)
    else:
        (parameters, inputs), path = GOOD_RUNS[model], built_fmus[model]
        slave = new_slave(model)
    expected = run_case(slave, parameters, inputs, name, value, 0.0)
    assert run_through_fmpy(path, parameters, inputs, name, value) == expected
    if expected[0] != "accepted":
        assert naming_problem(expected[1], name.rpartition(".")[2], value, expected[2]) is None, expected[1]
