"""What ``build_system_fmu`` (fmus/systemfmu/export.py) asks of the build for each role, with the
build recorded, not run (fast): the role's slave script and class, the target, the
variable-step flag (the loop takes any whole number of its steps per doStep: "true"; the chain
exactly one: "false"), the state options, the resources (system.json naming role and plant,
then nothing else for a system of parcosim models) and which components it takes (issue 31:
the options and the spec's role and plant were read back for no role)."""
from __future__ import annotations

import json

import pytest

from fmus.cosim.system import Component, Connection, System
from fmus.export.build import ROOT
from fmus.slave.registry import SLAVES
from fmus.systemfmu import export
from fmus.systemfmu.cores import SYSTEM_FILE, system_from_dict


@pytest.fixture
def calls(monkeypatch):
    """build_bundled_fmu recorded: (script, model, path, resource names, system.json, options)."""
    made = []

    def build_bundled_fmu(script, model, path, resources=(), **options):
        spec = [json.loads(r.read_text()) for r in resources if r.name == SYSTEM_FILE]
        made.append((script, model, path, [r.name for r in resources], spec, options))
        return path
    monkeypatch.setattr(export, "build_bundled_fmu", build_bundled_fmu)
    return made


SYSTEM = System((Component("traj", "Trajectory", {"kind": "hold"}), Component("deriv", "Derivator")),
                (Connection("traj.x_d", "deriv.u"),), ("deriv.y",), stop_time=0.02, step=2e-3)


@pytest.mark.parametrize("role, module, model, variable", [
    ("loop", "parcosim_closedloop", "ClosedLoop", "true"),
    ("chain", "parcosim_controlchain", "ControlChain", "false"),
])
def test_each_role_is_its_slave_with_its_step_flag_state_options_and_system(calls, tmp_path, role, module, model,
                                                                              variable):
    """Catches the roles' scripts, classes or step flags swapped or inverted, the state options
    (canGetAndSetFMUstate, canSerializeFMUstate) dropped, the system's spec not naming its role
    or plant, and another resource carried."""
    path = tmp_path / f"{model}.fmu"
    assert export.build_system_fmu(role, SYSTEM, path, plant="arm") == path
    ((script, built, target, names, spec, options),) = calls
    assert (script, built, target) == (ROOT / "fmus" / "slaves" / f"{module}.py", model, path)
    assert script.is_file()
    assert options == {"canHandleVariableCommunicationStepSize": variable, "canGetAndSetFMUstate": "true",
                       "canSerializeFMUstate": "true"}
    assert names == [SYSTEM_FILE]
    (spec,) = spec
    assert (spec["role"], spec["plant"]) == (role, "arm")
    carried = system_from_dict(spec["system"])
    assert (carried.components, carried.connections, carried.record) == \
        (SYSTEM.components, SYSTEM.connections, SYSTEM.record)


def test_the_plant_defaults_to_the_instance_named_plant(calls, tmp_path):
    export.build_system_fmu("chain", SYSTEM, tmp_path / "c.fmu")
    assert calls[0][4][0]["plant"] == "plant"


def test_every_component_not_a_model_nor_an_fmu_is_named_in_one_refusal(calls, tmp_path):
    """Only the unknown components are named, in the system's order, with every valid model.
    Catches a parcosim model or the and/or of the rule taken for unknown, and only the first
    unknown named."""
    system = System((Component("a", "Nope"), Component("traj", "Trajectory"), Component("b", "Neither.txt")),
                    (), (), 0.01)
    with pytest.raises(ValueError) as refused:
        export.build_system_fmu("loop", system, tmp_path / "x.FMU")   # the suffix in any case
    assert str(refused.value) == (f"cannot put a (Nope), b (Neither.txt) inside one FMU: a component is a parcosim "
                                  f"model ({', '.join(SLAVES)}) or an FMU file")
    assert calls == []
