"""The parameters a system FMU declares for its inner components (fmus/systemfmu/cores.py):
``instance.parameter`` for every parameter of every component, at the system's value where it
sets one, else the component's own start value with its type (an FMU file's read from its model
description, Booleans included); and a set of them given back to the right components only
(issue 31: every exported value read back exactly).  In process, fake FMUs: fast."""
from __future__ import annotations

from fmus.cosim.backends import InProcessInstance
from fmus.cosim.system import Component, Connection, System
from fmus.systemfmu.cores import component_parameters, system_from_dict, system_to_dict, with_parameters
from tests.fmus.export.test_oracles_export import TYPES, fake_fmu

START = {"Real": 0.0, "Integer": 0, "Boolean": False, "String": ""}


def _system(tmp_path):
    fmu = fake_fmu(tmp_path / "Ext.fmu", "Ext")
    return System((Component("traj", "Trajectory", {"side_time": 0.5}), Component("ext", str(fmu), {"gain": 2.5}),
                   Component("ext2", str(fmu), {"flag": True}, substeps=2)),
                  (Connection("traj.x_d", "ext.u"),), ("ext.y",), stop_time=0.25, step=2e-3)


def test_every_inner_parameter_is_declared_at_the_systems_value_or_its_own_start(tmp_path):
    """Catches a component's parameters left out or given another's, the system's value not
    taking precedence, a start value of an FMU file read as text (the Boolean "false" as True)
    or with another type."""
    system = _system(tmp_path)
    inst = InProcessInstance("Trajectory", "t")
    traj = {f"traj.{v.name}": getattr(inst.slave, v.name) for v in inst.variables.values()
            if v.causality == "parameter"}
    expected = {**traj, "traj.side_time": 0.5,
                **{f"ext.{name}": START[t] for name, t in TYPES.items()}, "ext.gain": 2.5,
                **{f"ext2.{name}": START[t] for name, t in TYPES.items()}, "ext2.flag": True}
    got = component_parameters(system)
    assert got == expected
    assert all(type(got[name]) is type(value) for name, value in expected.items())


def test_a_set_of_values_goes_back_to_its_components_only(tmp_path):
    """``ext.gain`` changes ext and not ext2 (a prefix without its dot would give ext's values
    to ext2 too); the rest of each component and of the system stays; system_to_dict and
    system_from_dict give the system back."""
    system = _system(tmp_path)
    changed = with_parameters(system, {"ext.gain": 3.0, "ext2.count": 7, "traj.kind": "triangle"})
    parameters = {c.name: c.parameters for c in changed.components}
    assert parameters == {"traj": {"side_time": 0.5, "kind": "triangle"}, "ext": {"gain": 3.0},
                          "ext2": {"flag": True, "count": 7}}
    assert [(c.name, c.model, c.substeps) for c in changed.components] == [
        (c.name, c.model, c.substeps) for c in system.components]
    assert (changed.connections, changed.record, changed.stop_time, changed.step) == (
        system.connections, system.record, system.stop_time, system.step)
    assert system_from_dict(system_to_dict(changed)) == changed
