"""A package's run in another tool says why it stopped as data (issue 29 item 2; docs/contract.md,
"A package's run in another tool").

The same refusing package runs in our master (through the FMUs), in fmpy (its SSP runner with
the package's bindings, and plainly), in Ecos and in libcosim; each run's ``error`` is a
:class:`fmus.status.RunError` read from the refusing FMU's String output ``refusal``, with the
fields our master gives.  A foreign FMU, which has no such output, gets a record of kind,
instance (where the tool says it) and time, and the tool's message.
"""
from __future__ import annotations

import dataclasses
import math
import zipfile

import pytest

from fmus.cosim.master import simulate
from fmus.cosim.system import Component, System
from fmus.ssp.export import NS, export_ssp
from fmus.ssp.run import simulate_ssp_ecos, simulate_ssp_fmpy, tool_refusal
from fmus.status import RunError, RunStatus
from scenarios.studies.tools import run_tool
from tests.support.tools import UNAVAILABLE

pytestmark = [pytest.mark.fmu, pytest.mark.tools]

#: The fields compared exactly (the time and the value: to a few ulps of the model's clock,
#: which libcosim keeps as k h in integer nanoseconds, our master and fmpy as t + h).
EXACT = ("kind", "instance", "variable", "unit", "code", "reason", "message")
H = 1e-3


def _open_loop(**plant) -> System:
    """The bench plant alone under 0.3 N m: it reaches a singular pose near t = 0.2 s and its
    kernel refuses the step (a model's record: variable, value, code, reason "singular")."""
    parameters = {"preset": "bench", "x0": -0.002, "y0": 0.108, "tau1": 0.3, "tau2": -0.3, **plant}
    return System((Component("plant", "FiveBarPlant", parameters),), (), ("plant.x", "plant.y"), stop_time=0.3)


def _run(tool: str, path):
    """The error of the package's run in ``tool`` (skipped where the tool does not load)."""
    if UNAVAILABLE.get(tool.split()[0]):
        pytest.skip(f"{tool}: {UNAVAILABLE[tool.split()[0]]}")
    if tool == "fmpy":
        return simulate_ssp_fmpy(path).error
    if tool == "fmpy plain":
        return run_tool("fmpy", path, ["plant.x"], 0.3, H).error
    if tool == "ecos":
        return simulate_ssp_ecos(path, ["plant.x"]).error
    from fmus.ssp.libcosim import simulate_ssp_libcosim

    return simulate_ssp_libcosim(path, ["plant.x"], isolated=True).error


TOOLS = ("fmpy", "fmpy plain", "ecos", "libcosim")


@pytest.fixture(scope="module", params=["refused step", "refused initialisation"])
def refusing(request, built_fmus, tmp_path_factory):
    """(package, our master's error through the same FMUs) of a plant that refuses a step (the
    singular pose) or its initialisation (x0 = 5 m, out of reach)."""
    fmu_dir = next(iter(built_fmus.values())).parent
    system = _open_loop() if request.param == "refused step" else _open_loop(x0=5.0)
    master = simulate(system, mode="fmu", fmu_dir=fmu_dir).error
    kind = RunStatus.REFUSED if request.param == "refused step" else RunStatus.INITIALISATION
    assert isinstance(master, RunError) and master.kind is kind and master.instance == "plant"
    return export_ssp(system, tmp_path_factory.mktemp("ssp") / "refusing.ssp", fmu_dir), master


@pytest.mark.parametrize("tool", TOOLS)
def test_a_refusal_in_each_tool_is_the_masters_record(refusing, tool):
    """Catches a tool's run that reports its refusal as text, loses the model's fields (variable,
    value, code, reason), names the FMU by the tool's instance name (Ecos instantiates it under
    its unpacked path) or by none, or reads a stale ``error`` instead of the record."""
    path, master = refusing
    error = _run(tool, path)
    assert isinstance(error, RunError), error
    assert [getattr(error, f) for f in EXACT] == [getattr(master, f) for f in EXACT]
    assert error.time == pytest.approx(master.time, rel=0, abs=1e-12)
    if master.value is None:
        assert error.value is None
    else:
        assert math.isfinite(error.value) and error.value == pytest.approx(master.value, rel=1e-6)
    assert error.record()["kind"] == master.kind.value


REFUSER = '''
from pythonfmu import Fmi2Slave, Fmi2Causality, Real


class Refuser(Fmi2Slave):
    """A foreign FMU: refuses (fmi2Discard) every step from t = 2 ms on; no output 'refusal'."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.y = 0.0
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.y = current_time + step_size
        return current_time < 0.002 - 1e-9
'''


@pytest.fixture(scope="module")
def foreign(tmp_path_factory):
    """(package of one foreign FMU that refuses the step from 2 ms, the FMU's path)."""
    from pythonfmu import FmuBuilder

    folder = tmp_path_factory.mktemp("foreign")
    (folder / "Refuser.py").write_text(REFUSER)
    fmu = FmuBuilder.build_FMU(folder / "Refuser.py", dest=folder)
    ssd = f"""<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="{NS['ssd']}" xmlns:ssc="{NS['ssc']}" version="1.0" name="r">
  <ssd:System name="r"><ssd:Elements>
    <ssd:Component name="bad" type="application/x-fmu-sharedlibrary" source="resources/Refuser.fmu"/>
  </ssd:Elements></ssd:System>
  <ssd:DefaultExperiment startTime="0.0" stopTime="0.005"/>
</ssd:SystemStructureDescription>
"""
    path = folder / "foreign.ssp"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("SystemStructure.ssd", ssd)
        zf.write(fmu, "resources/Refuser.fmu")
    return path, fmu


def test_a_foreign_fmus_refusal_is_a_record_with_the_tools_message(foreign):
    """Catches a foreign FMU's refusal that is lost, raised as an exception or given a made-up
    model field: fmpy says who and when, libcosim when (not who); the model's fields are None;
    Ecos steps on (it does not report a refused step) and records every row."""
    path, fmu = foreign
    master = simulate(System((Component("bad", str(fmu)),), (), ("bad.y",), stop_time=0.005)).error
    assert (master.kind, master.instance, master.time) == (RunStatus.REFUSED, "bad", 0.002)
    model = ("variable", "value", "unit", "code", "reason")
    fmpy_error = simulate_ssp_fmpy(path, step_size=H).error
    assert (fmpy_error.kind, fmpy_error.instance, fmpy_error.time) == (master.kind, master.instance, master.time)
    assert "status 2" in fmpy_error.message and all(getattr(fmpy_error, f) is None for f in model)
    assert run_tool("fmpy", path, ["bad.y"], 0.005, H).error == fmpy_error
    if not UNAVAILABLE["libcosim"]:
        from fmus.ssp.libcosim import simulate_ssp_libcosim

        run = simulate_ssp_libcosim(path, ["bad.y"], step_size=H, isolated=True)
        error = run.error
        assert (error.kind, error.instance, error.time) == (RunStatus.REFUSED, None, 0.002)
        assert all(getattr(error, f) is None for f in model) and len(run.time) == 3
    if not UNAVAILABLE["ecos"]:
        run = simulate_ssp_ecos(path, ["bad.y"], step_size=H)
        assert run.error is None and len(run.time) == 6


def test_a_system_fmus_inner_component_follows_the_tools_instance_name():
    """Catches the inner component of a system FMU's record lost, or the tool's own instance
    name (Ecos: the FMU's unpacked path) kept, when the record is named after the package's
    component."""
    inner = RunError(RunStatus.REFUSED, "x0 = 5.0 out of reach", instance="/tmp/u/resources/chain.fmu.plant",
                     time=0.0, variable="x0", value=5.0)
    error = tool_refusal("chain", 0.0, inner.to_json(), "", named="/tmp/u/resources/chain.fmu")
    assert (error.instance, error.variable, error.value) == ("chain.plant", "x0", 5.0)
    assert error.message == "chain refused the step from t = 0 s: x0 = 5.0 out of reach"
    atomic = dataclasses.replace(inner, instance="chain")
    assert tool_refusal("chain", 0.0, atomic.to_json(), "").instance == "chain"
    foreign = tool_refusal(None, 0.003, "", "  Step not complete ")
    assert (foreign.instance, foreign.time, foreign.message, foreign.code) == (None, 0.003, "Step not complete", None)


def test_only_a_dot_after_the_tools_instance_name_starts_an_inner_component():
    """A record of an instance whose name merely begins with the FMU's ("chain2" under "chain",
    "chain.fmux" under the path "chain.fmu") is no inner component of it: the error is the
    package's component alone.  Catches the separator dropped from the prefix test (seed 4001's
    survivor [267], ``named + "."`` -> ``named``: "chain" + "2")."""
    for named, recorded in (("chain", "chain2"), ("/tmp/u/resources/chain.fmu", "/tmp/u/resources/chain.fmux")):
        record = RunError(RunStatus.REFUSED, "x0 = 5.0 out of reach", instance=recorded, time=0.0)
        assert tool_refusal("chain", 0.0, record.to_json(), "", named=named).instance == "chain"
