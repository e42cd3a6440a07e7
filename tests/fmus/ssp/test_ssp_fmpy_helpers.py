"""fmus/ssp/run.py's helpers around fmpy's SSP runner, on made-up packages and components: the
package's bindings as fmpy's parameter set, each value with its FMI type (fmpy would take the
XML string "false" for True), and a component's String output read back or "" whenever it
cannot be (issue 31: these ran only inside whole fmpy runs, with one type each)."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from fmus.cosim.system import Component, Connection, System
from fmus.ssp.export import export_ssp
from fmus.ssp.run import PARAMETER_SET, _fmpy_string, fmpy_parameter_set
from fmus.status import RunStatus
from tests.fmus.export.test_oracles_export import fake_fmu


def test_the_parameter_set_is_every_binding_with_its_fmi_type_and_typed_value(tmp_path):
    """Catches a value passed as its XML text (True as "true", 7 as "7"), a type taken from
    another value, a binding left out, or the set misnamed."""
    fmus = {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}
    values = {"gain": -2.5, "count": 7, "flag": False, "label": "ab c"}
    system = System((Component("first", "Alpha", values), Component("second", "Beta", {"flag": True})),
                    (Connection("first.y", "second.u"),), ("second.y",), stop_time=0.5, step=2e-3)
    pset = fmpy_parameter_set(export_ssp(system, tmp_path / "p.ssp", fmus=fmus))
    assert pset.name == PARAMETER_SET
    got = {p.name: (p.type, p.value, type(p.value)) for p in pset.parameters}
    assert got == {"first.gain": ("Real", -2.5, float), "first.count": ("Integer", 7, int),
                   "first.flag": ("Boolean", False, bool), "first.label": ("String", "ab c", str),
                   "second.flag": ("Boolean", True, bool)}


class _FMU:
    def __init__(self, value):
        self.value = value

    def getString(self, refs):
        if isinstance(self.value, Exception):
            raise self.value
        return [self.value]


def _component(value, type_="String", causality="output", name="refusal"):
    variable = SimpleNamespace(type=type_, causality=causality, valueReference=4)
    return SimpleNamespace(variables={name: variable}, fmu=_FMU(value))


@pytest.mark.parametrize("component, expected", [
    (_component(b"plant: q1 = nan"), "plant: q1 = nan"),
    (_component("as text"), "as text"),
    (_component(b"bad \xff byte"), "bad \ufffd byte"),
    (_component(None), ""),
    (_component(RuntimeError("freed")), ""),
    (_component(b"x", type_="Real"), ""),
    (_component(b"x", causality="input"), ""),
    (_component(b"x", name="error"), ""),
    (SimpleNamespace(fmu=_FMU(b"x")), ""),
])
def test_a_components_string_output_is_read_or_empty_when_it_cannot_be(component, expected):
    """Catches bytes not decoded (or decoded strictly: an error instead of the message), a
    variable of another type, causality or name read, and a failed read raised instead of
    leaving the tool's own message."""
    assert _fmpy_string(component, "refusal") == expected


class _Freed:
    def __init__(self):
        self.calls = []

    def terminate(self):
        self.calls.append("terminate")

    def freeInstance(self):
        self.calls.append("freeInstance")


@pytest.mark.parametrize("fails, expected", [
    ("instantiate", (RunStatus.INITIALISATION, "foreign", 0.0)),
    ("step", (RunStatus.REFUSED, "foreign", 0.25)),
])
def test_fmpy_watch_records_the_call_a_foreign_fmu_failed_and_frees_every_fmu(monkeypatch, fails, expected):
    """Catches the watch giving a foreign FMU's failure (no ``refusal`` output) the wrong kind,
    instance or time (initialisation not at t = 0, a step not at its start), an FMU left
    instantiated, or fmpy's functions not called through and restored."""
    import fmpy.ssp.simulation as sim
    from fmus.ssp.run import fmpy_watch

    seen = []

    def instantiate(component, *args, **kwargs):
        seen.append(("instantiate", component.name, args))
        if fails == "instantiate" and component.name == "foreign":
            raise RuntimeError("fmi2Instantiate failed")

    def step(component, time, step_size):
        seen.append(("step", component.name, time, step_size))
        raise RuntimeError("fmi2DoStep returned fmi2Error")

    monkeypatch.setattr(sim, "instantiate_fmu", instantiate)
    monkeypatch.setattr(sim, "do_step", step)
    ours, foreign = (SimpleNamespace(name=n, variables={}, fmu=_Freed()) for n in ("ours", "foreign"))
    with fmpy_watch() as watch:
        try:
            sim.instantiate_fmu(ours, 0.0)
            sim.instantiate_fmu(foreign, 0.0)
            sim.do_step(foreign, 0.25, 0.05)
        except RuntimeError as exc:
            error = watch.refusal(exc)
    assert (sim.instantiate_fmu, sim.do_step) == (instantiate, step)
    assert (error.kind, error.instance, error.time) == expected and str(error) == error.message
    assert error.message == ("fmi2Instantiate failed" if fails == "instantiate" else "fmi2DoStep returned fmi2Error")
    assert seen[:2] == [("instantiate", "ours", (0.0,)), ("instantiate", "foreign", (0.0,))]
    assert ours.fmu.calls == foreign.fmu.calls == ["terminate", "freeInstance"]
