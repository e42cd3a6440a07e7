"""The native FMUs as FMI 3.0 co-simulation FMUs (issue 28, item 7; docs/native.md "FMI 3.0").

`parcosim build --native --fmi-version 3` compiles the same core and adapters under the FMI
3.0 layer (fmus/native/fmi3_native.c).  Each FMI 3.0 FMU runs the equality script of
tests/fmus/native/test_native_equality.py against its FMI 2.0 native twin through fmpy: every status
equal, every message equal once FMI 2.0's function names are written as FMI 3.0's, every
value read bit for bit; also sub-stepped, in fmpy's simulate_fmu, from its own sources with
strict warnings, and under AddressSanitizer/UBSan.  Wrong code it catches: the layer reading
an Int32 or Boolean array as another width, a state of another layout or checksum, a
description whose value references or starts differ from the FMI 2.0 one, fmi3DoStep
outputs that do not say where the step ended, a message naming the wrong function.
"""
from __future__ import annotations

import ctypes
import math
import shutil
import subprocess
import sys
import zipfile

import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave, fmi3Boolean, fmi3Float64, fmi3ValueReference
from fmpy.validation import validate_fmu

from fmus.native.build import compile_command, platform_folder
from fmus.native.models import NATIVE
from fmus.native.state_bytes import layout
from parcosim.cli import main
from tests.fmus.native.test_native_build import ALLOWED, STRICT, needed
from tests.fmus.native.test_native_equality import SAMPLED, SCENARIOS, Scenario, outputs, script
from tests.support.fmu3_calls import Driver3, as_fmi3
from tests.support.fmu_calls import Driver
from tests.support.paths import ROOT, TESTS

pytestmark = pytest.mark.fmu
MODELS = sorted(NATIVE)


@pytest.fixture(scope="session")
def native3_fmus(tmp_path_factory):
    """Model name -> its FMI 3.0 native FMU, written by the command line."""
    out = tmp_path_factory.mktemp("native3")
    assert main(["build", "--native", "--fmi-version", "3", "--out", str(out)]) == 0
    return {path.stem: path for path in out.glob("*.fmu")}


def _run(driver, calls):
    trace = []
    for call in calls:
        if call[0] in ("serialize", "deserialize"):   # (op, state key, bytes key)
            fmi3 = isinstance(driver, Driver3)
            name = {"serialize": ("serializeFMUstate", "serializeFMUState"),
                    "deserialize": ("deSerializeFMUstate", "deserializeFMUState")}[call[0]][fmi3]
            trace.append(driver.call("bytes", call[2], getattr(driver.fmu, name)(driver.states[call[1]])))
        else:
            trace.append(driver.call(*call))
    return trace


def _same(a, b) -> bool:
    return a == b or (isinstance(a, float) and math.isnan(a) and math.isnan(b))


def compare(fmi2_path, fmi3_path, scenario: Scenario, parameters: dict, extra=lambda outs: []) -> list:
    """The equality script on both FMUs: statuses, messages (in FMI 3.0's names) and every value
    read equal; returns the FMI 2.0 trace."""
    two, three = Driver(fmi2_path), Driver3(fmi3_path)
    outs = outputs(two)
    assert outputs(three) == outs
    real = next(v.name for v in two.md.modelVariables if v.causality == "output" and v.type == "Real")
    calls = script(scenario, parameters, outs, real)
    end = calls.index(("terminate",))
    calls[end:end] = extra(outs)
    trace2, trace3 = _run(two, calls), _run(three, calls)
    statuses = [s.status for s in trace2]
    assert statuses.count(2) >= 2 and statuses.count(3) >= 2   # the script reaches a refused step and call
    for a, b in zip(trace2, trace3, strict=True):
        assert b.status == a.status, (a.call, a.messages, b.messages)
        assert b.messages == [(s, c, as_fmi3(m)) for s, c, m in a.messages], a.call
        if a.call[0] == "get":
            assert all(_same(x, y) for x, y in zip(a.result, b.result, strict=True)), (a.call, a.result, b.result)
    two.close()
    three.close()
    return trace2


@pytest.mark.parametrize("model", MODELS)
def test_fmi3_fmu_equals_its_fmi2_twin_call_by_call(model, native_fmus, native3_fmus):
    """The first two parameter sets of the model's equality scenario and its last (refused) one."""
    scenario = SCENARIOS[model]
    for parameters in [*scenario.parameters[:2], scenario.parameters[-1]]:
        compare(native_fmus[model], native3_fmus[model], scenario, parameters)


@pytest.mark.parametrize("model", SAMPLED)
def test_substepped_fmi3_fmu_equals_its_fmi2_twin(model, native_fmus, native3_fmus):
    """h = T / 4 sampled on sub-step 2, the state restored mid-period, a step of h / 2 there refused."""
    base = SCENARIOS[model]
    h = float(Driver(native_fmus[model]).variables["T"].start) / 4
    scenario = Scenario(h, base.inputs, bad_input=base.bad_input, fixed=base.fixed, steps=base.steps)
    mark = (scenario.steps // 3 + 1) * h

    def period_change(outs):
        return [("setstate", "s"), ("step", mark, h / 2), ("get", outs), ("setstate", "s"), ("step", mark, h)]

    trace = compare(native_fmus[model], native3_fmus[model], scenario, {"sample_phase": 2}, period_change)
    assert "changes the step within a sample period" in " ".join(m[2] for s in trace for m in s.messages)


@pytest.mark.parametrize("model", MODELS)
def test_fmi3_fmu_validates_and_declares_the_fmi2_variables(model, native_fmus, native3_fmus, tmp_path):
    """Catches an FMI 3.0 native FMU whose variables, references, outputs or binary differ from its FMI 2.0
    twin's, that reuses its GUID, or that fmpy's validation refuses."""
    fmu = native3_fmus[model]
    assert validate_fmu(str(fmu)) == []
    md2, md3 = read_model_description(str(native_fmus[model])), read_model_description(str(fmu))
    assert md3.fmiVersion == "3.0" and md3.guid != md2.guid
    assert md3.coSimulation.hasEventMode is False and md3.coSimulation.canGetAndSetFMUstate is True
    names = {"Real": "Float64", "Integer": "Int32"}
    assert [(v.name, v.valueReference, names.get(v.type, v.type), v.causality, v.start) for v in md2.modelVariables] \
        == [(v.name, v.valueReference, v.type, v.causality, v.start) for v in md3.modelVariables
            if v.causality != "independent"]
    (time,) = [v for v in md3.modelVariables if v.causality == "independent"]
    assert time.name == "time" and time.valueReference == 1 + max(v.valueReference for v in md2.modelVariables)
    assert [u.variable.name for u in md3.outputs] == [u.variable.name for u in md2.outputs]
    with zipfile.ZipFile(fmu) as z:
        z.extractall(tmp_path)
        build = z.read("sources/buildDescription.xml").decode()
    assert "fmi3_native.c" in build and "fmi2_native.c" not in build
    assert needed(tmp_path / "binaries" / platform_folder(3) / f"{model}.so") <= ALLOWED


@pytest.mark.parametrize("model", MODELS)
def test_simulate_fmu_runs_the_fmi3_fmu_as_its_fmi2_twin(model, native_fmus, native3_fmus):
    """Catches the FMI 3.0 entry points stepping the same C otherwise than FMI 2.0's (a time or step size
    passed differently)."""
    experiment = read_model_description(str(native_fmus[model])).defaultExperiment
    step = float(experiment.stepSize) if experiment and experiment.stepSize else 1e-3
    runs = [simulate_fmu(str(path), stop_time=40 * step, step_size=step, output_interval=step,
                         fmi_type="CoSimulation") for path in (native_fmus[model], native3_fmus[model])]
    for name in runs[0].dtype.names:
        assert list(runs[0][name]) == list(runs[1][name]), name


def test_state_has_the_fmi2_layout_and_is_refused_across_versions(native_fmus, native3_fmus):
    """The same bytes but the GUID and checksum; each version refuses the other's state by GUID, a
    flipped byte by checksum; serialise, deserialise, serialise gives the bytes back."""
    model = "FiveBarPlant"
    two, three = Driver(native_fmus[model]), Driver3(native3_fmus[model])
    inputs = SCENARIOS[model].inputs
    for driver in (two, three):
        assert [driver.call(*c).status for c in [("setup", 0.0), ("enter",), ("exit",)]] == [0, 0, 0]
        for k in range(5):
            driver.call("set", inputs(k, k * 1e-3))
            assert driver.call("step", k * 1e-3, 1e-3).status == 0
    s2 = two.fmu.serializeFMUstate(two.fmu.getFMUstate())
    state3 = three.fmu.getFMUState()
    s3 = three.fmu.serializeFMUState(state3)
    where2, where3 = layout(s2), layout(s3)
    assert len(s2) == len(s3) and where2["data_offset"] == where3["data_offset"]
    assert where2["guid"] == read_model_description(str(native_fmus[model])).guid
    assert where3["guid"] == read_model_description(str(native3_fmus[model])).guid
    start = where2["sizes"][2][0] + 2   # the GUID's bytes, after its u16 length
    guid = slice(start, start + len(where2["guid"]))
    assert s2[:guid.start] == s3[:guid.start] and s2[guid.stop:-8] == s3[guid.stop:-8]
    assert three.fmu.serializeFMUState(three.fmu.deserializeFMUState(s3)) == s3
    flipped = bytearray(s3)
    flipped[where3["data_offset"]] ^= 1
    for driver, data in [(three, s2), (two, s3), (three, bytes(flipped))]:
        driver.call("bytes", "other", data)
        step = driver.call("deserialize", "other")
        assert step.status == 3, step.messages
    assert step.messages[0][2].startswith("fmi3DeserializeFMUState: the state refused:")
    assert "the state's checksum does not match its bytes" in step.messages[0][2]
    three.call("bytes", "other", s2)
    assert "this FMU's GUID is" in three.call("deserialize", "other").messages[0][2]


def test_fmi3_calls_of_its_own(native3_fmus, tmp_path):
    """fmi3DoStep's outputs (where the step ended, no event, no early return), the independent
    variable, nValues, types without variables, Event Mode and instantiation refused by name."""
    model = "Derivator"
    d = Driver3(native3_fmus[model], unzipped=extract(str(native3_fmus[model]), str(tmp_path)))
    f, c = d.fmu, d.fmu.component
    time_vr = next(v.valueReference for v in d.md.modelVariables if v.causality == "independent")
    f.enterInitializationMode(startTime=0.25)
    assert f.getFloat64([time_vr]) == [0.25]
    f.exitInitializationMode()
    flags = [fmi3Boolean(True) for _ in range(3)]
    end = fmi3Float64(-1.0)

    def do_step(t, h):
        try:
            status = f.fmi3DoStep(c, t, h, True, *(ctypes.byref(b) for b in flags), ctypes.byref(end))
        except FMICallException as exc:
            status = exc.status
        return status, [b.value for b in flags], end.value

    assert do_step(0.25, 1e-3) == (0, [False, False, False], 0.25 + 1e-3)
    assert f.getFloat64([time_vr, d.variables["dq1"].valueReference])[0] == 0.25 + 1e-3
    status, _, last = do_step(0.25 + 1e-3, 2.5e-3)   # does not divide T: refused, nothing advanced
    assert (status, last) == (2, 0.25 + 1e-3)
    d.log.clear()
    vr = (fmi3ValueReference * 1)(d.variables["q1"].valueReference)
    with pytest.raises(FMICallException):
        f.fmi3SetFloat64(c, vr, 1, (fmi3Float64 * 2)(), 2)
    assert "nValues = 2 for 1 value references refused" in d.log[-1][2]
    for call, says in [(lambda: f.setFloat64([time_vr], [1.0]), "('time') is the independent variable"),
                       (lambda: f.getFloat32([vr[0]]), "('q1') is a Float64 variable, not a Float32"),
                       (lambda: f.enterEventMode(), "fmi3EnterEventMode: not supported: this FMU has no Event Mode")]:
        d.log.clear()
        with pytest.raises(Exception):
            call()
        assert says in d.log[-1][2], d.log
    assert f.getUInt64([]) == []
    d.close()
    log = []
    other = FMU3Slave(guid=d.md.guid, unzipDirectory=d.dir, modelIdentifier=model, instanceName="ev")
    with pytest.raises(Exception, match="Failed to instantiate"):
        other.instantiate(eventModeUsed=True, logMessage=lambda env, s, cat, m: log.append(m.decode()))
    assert log == ["fmi3InstantiateCoSimulation: eventModeUsed refused: Derivator has no Event Mode "
                   '(hasEventMode="false")']


@pytest.mark.parametrize("model", ["Derivator", "ActuatedFiveBarPlant"])
def test_fmi3_fmu_compiled_from_its_own_sources_runs_as_shipped(model, native3_fmus, tmp_path):
    """Its sources/ and fmpy's FMI 3.0 headers alone, with the kernels' strict warnings as errors."""
    fmu = native3_fmus[model]
    folder = tmp_path / "rebuilt"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    sources = tmp_path / "only_sources"
    shutil.copytree(folder / "sources", sources)
    binary = folder / "binaries" / platform_folder(3) / f"{model}.so"
    binary.unlink()
    command = compile_command(sources, binary)
    subprocess.run([command[0], *STRICT, *command[1:]], check=True, capture_output=True)
    shipped = simulate_fmu(str(fmu), stop_time=0.05, output_interval=1e-3, step_size=1e-3)
    again = simulate_fmu(str(folder), stop_time=0.05, output_interval=1e-3, step_size=1e-3)
    for name in shipped.dtype.names:
        assert list(shipped[name]) == list(again[name]), name


def test_cli_refuses_an_fmi_version_without_native(capsys):
    assert main(["build", "--fmi-version", "3", "--out", "unused_dir"]) != 0
    assert "--fmi-version 3 is for the native FMUs: it needs --native" in capsys.readouterr().err


@pytest.mark.tools
def test_fmi3_fmu_survives_careless_calls_and_forged_states_under_asan(native_fmus, native3_fmus, tmp_path):
    """The DC motor drive (current mode: the sampled counter, the observer) rebuilt with the
    sanitizers and driven by tests/support/native_fuzz3.py; the FMI 2.0 twin's state among the forged."""
    from tests.fmus.native.test_native_sanitized import SANITIZE
    from tests.kernels.test_sanitizers import ASAN, _sanitized_env

    if ASAN is None:
        pytest.skip("the C compiler has no AddressSanitizer runtime")
    model = "DCMotorDrive"
    folder = tmp_path / "fmu"
    with zipfile.ZipFile(native3_fmus[model]) as z:
        z.extractall(folder)
    binary = folder / "binaries" / platform_folder(3) / f"{model}.so"
    command = compile_command(folder / "sources", binary)
    subprocess.run([command[0], *SANITIZE, *command[1:]], check=True, capture_output=True)
    two = Driver(native_fmus[model])
    for call in [("setup", 0.0), ("enter",), ("exit",), ("step", 0.0, 1e-3)]:
        two.call(*call)
    state = tmp_path / "fmi2_state.bin"
    state.write_bytes(two.fmu.serializeFMUstate(two.fmu.getFMUstate()))
    env = _sanitized_env(binary)
    env["PYTHONPATH"] = str(ROOT)
    worker = TESTS / "support" / "native_fuzz3.py"
    run = subprocess.run([sys.executable, str(worker), str(folder), "36", str(state)], env=env,
                         capture_output=True, text=True, errors="backslashreplace", timeout=300)
    assert run.returncode == 0 and "survived" in run.stdout, run.stderr[-3000:]
    assert "3 of 3 instantiations refused" in run.stdout, run.stdout


@pytest.mark.slow
def test_fmi3_closed_loop_equals_the_fmi2_one(native_loop_fmu, tmp_path):
    """`export-fmu SCENE OUT.fmu --native --fmi-version 3`: the whole loop under FMI 3.0, every
    output of fmpy's run equal to the FMI 2.0 native ClosedLoop's, bit for bit."""
    from tests.conftest import LOOP_SCENE

    path = tmp_path / "ClosedLoop.fmu"
    assert main(["export-fmu", LOOP_SCENE, str(path), "--native", "--fmi-version", "3"]) == 0
    assert validate_fmu(str(path)) == [] and read_model_description(str(path)).fmiVersion == "3.0"
    runs = [simulate_fmu(str(p), stop_time=0.5, output_interval=1e-3, fmi_type="CoSimulation")
            for p in (native_loop_fmu, path)]
    assert runs[0].dtype.names == runs[1].dtype.names and len(runs[0]) == 501
    for name in runs[0].dtype.names:
        assert list(runs[0][name]) == list(runs[1][name]), name
