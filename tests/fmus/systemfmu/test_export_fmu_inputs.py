"""What a system FMU's build takes and writes before pythonfmu runs (fmus/systemfmu/export.py):
an FMU-file component carried in the resources (byte for byte, renamed by its instance, the
system naming it there), the loop's record with the plant's x, y first, copies of an FMU with
other start values read back exactly, and each refusal naming what it refused (issue 31:
every exported value read back; error paths naming the value).  The build itself is recorded,
not run: fast."""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET
import zipfile

import pytest

from fmus.cosim.system import Component, Connection, System
from fmus.slave.base import START_VALUES_FILE
from fmus.systemfmu import export
from fmus.systemfmu.cores import FOREIGN_DIR, SYSTEM_FILE, system_from_dict
from tests.fmus.export.test_oracles_export import AWKWARD, TYPES, fake_fmu


@pytest.fixture
def recorded(monkeypatch):
    """build_bundled_fmu replaced by a recorder of its resources (name -> bytes, folders walked)."""
    built = {}

    def build_bundled_fmu(script, model, path, resources=(), **options):
        files = {}
        for item in resources:
            paths = [item] if item.is_file() else sorted(p for p in item.rglob("*") if p.is_file())
            files.update({p.relative_to(item.parent).as_posix(): p.read_bytes() for p in paths})
        built.update(model=model, files=files, options=options)
        return path
    monkeypatch.setattr(export, "build_bundled_fmu", build_bundled_fmu)
    return built


def test_an_fmu_file_component_travels_in_the_resources_under_its_instance_name(recorded, tmp_path):
    """Catches the foreign FMU not copied, copied under another name or changed, and the system
    in system.json still naming the builder's path (which the importer's machine has not)."""
    fmu = fake_fmu(tmp_path / "Other.fmu", "Other")
    system = System((Component("traj", "Trajectory"), Component("ext", str(fmu), {"gain": 2.5})),
                    (Connection("traj.x_d", "ext.u"),), ("ext.y",), stop_time=0.01, step=1e-3)
    export.build_system_fmu("loop", system, tmp_path / "Loop.fmu")
    assert recorded["files"][f"{FOREIGN_DIR}/ext.fmu"] == fmu.read_bytes()
    spec = json.loads(recorded["files"][SYSTEM_FILE])
    carried = system_from_dict(spec["system"])
    assert [c.model for c in carried.components] == ["Trajectory", f"{FOREIGN_DIR}/ext.fmu"]
    assert carried.components[1].parameters == {"gain": 2.5}
    assert (carried.connections, carried.record, carried.step) == (system.connections, system.record, system.step)


@pytest.mark.parametrize("make, message", [
    (lambda tmp: ("chain3", System((Component("traj", "Trajectory"),), (), (), 0.01), tmp / "a.fmu"),
     r"role = 'chain3'; valid: loop, chain"),
    (lambda tmp: ("loop", System((Component("traj", "Trajectory"),), (), (), 0.01), tmp / "a.zip"),
     r"a.zip: an FMU file must end in '.fmu'"),
    (lambda tmp: ("loop", System((Component("traj", "Nonsense"),), (), (), 0.01), tmp / "a.fmu"),
     r"cannot put traj \(Nonsense\) inside one FMU: a component is a parcosim model \(.*\) or an FMU file"),
    (lambda tmp: ("loop", System((Component("ext", str(tmp / "missing.fmu")),), (), (), 0.01), tmp / "a.fmu"),
     r"component ext: no FMU file .*missing.fmu"),
])
def test_what_cannot_be_built_is_refused_naming_it(recorded, tmp_path, make, message):
    role, system, path = make(tmp_path)
    with pytest.raises(ValueError, match=message):
        export.build_system_fmu(role, system, path)
    assert recorded == {}


def test_the_loop_records_the_plants_position_first_once():
    """Catches x, y left out, repeated, or put after the scene's own record; and a system
    without a plant taken (its FMU would have no x, y)."""
    system = System((Component("plant", "FiveBarPlant"), Component("traj", "Trajectory")), (),
                    ("traj.x_d", "plant.y", "traj.y_d"), stop_time=0.5, step=2e-3)
    loop = export.closed_loop_system(system)
    assert loop.record == ("plant.x", "plant.y", "traj.x_d", "traj.y_d")
    assert (loop.components, loop.connections, loop.stop_time, loop.step) == (
        system.components, system.connections, 0.5, 2e-3)
    with pytest.raises(ValueError, match=r"needs a component 'plant' .*; it has \['traj'\]"):
        export.closed_loop_system(System((Component("traj", "Trajectory"),), (), (), 0.5))


def test_a_copy_with_start_values_reads_back_each_value_with_its_type(tmp_path):
    """with_start_values: the model description's ``start`` attributes and
    ``resources/start_values.json`` hold every value given, read back exactly with its type
    (17 digits, the int32 ends, "true"/"false", XML's special characters); every other member is
    the original's; a variable the FMU lacks is refused naming it, and no file is written."""
    fmu = fake_fmu(tmp_path / "Alpha.fmu", "Alpha")
    copy = export.with_start_values(fmu, dict(AWKWARD), tmp_path / "copy.fmu")
    readers = {"Real": float, "Integer": int, "Boolean": {"true": True, "false": False}.__getitem__, "String": str}
    with zipfile.ZipFile(copy) as z, zipfile.ZipFile(fmu) as original:
        root = ET.fromstring(z.read("modelDescription.xml"))
        starts = {sv.get("name"): next(iter(sv)) for sv in root.iter("ScalarVariable")}
        read = {name: readers[starts[name].tag](starts[name].get("start")) for name in AWKWARD}
        assert read == AWKWARD and all(type(read[n]) is type(v) for n, v in AWKWARD.items())
        assert {name: starts[name].tag for name in AWKWARD} == TYPES
        assert json.loads(z.read(f"resources/{START_VALUES_FILE}")) == AWKWARD
        assert set(z.namelist()) == set(original.namelist()) | {f"resources/{START_VALUES_FILE}"}
    with pytest.raises(ValueError, match=r"Alpha.fmu has no variables \['nope'\]"):
        export.with_start_values(fmu, {"gain": 1.0, "nope": 2.0}, tmp_path / "never.fmu")
    assert not (tmp_path / "never.fmu").exists()


@pytest.mark.parametrize("carried", ["designs", "slavemodule"])
def test_a_copy_of_an_fmu_with_only_one_of_the_designs_markers_keeps_its_members(tmp_path, carried):
    """Designs are computed for a copy only when the FMU carries both a designs file and the
    name of its slave's module (one of ours whose initialisation computes designs); with
    either alone it is not, and the copy keeps every member as it was (none computed, none
    refused for lacking the other)."""
    from fmus.export.bundle import bundle_name
    from fmus.slave.designs import DESIGNS_FILE
    from fmus.slave.identity import IDENTITY_FILE

    carried = f"resources/{DESIGNS_FILE}" if carried == "designs" else "resources/slavemodule.txt"
    fmu = fake_fmu(tmp_path / "Alpha.fmu", "Alpha")
    members = {carried: b"fmus.slaves.parcosim_dcmotordrive" if carried.endswith(".txt") else b"its own designs",
               f"resources/{IDENTITY_FILE}": json.dumps({"package": bundle_name(), "model": "DCMotorDrive"})}
    with zipfile.ZipFile(fmu, "a") as z:
        for name, data in members.items():
            z.writestr(name, data)
    copy = export.with_start_values(fmu, {"gain": 2.0}, tmp_path / "copy.fmu")
    with zipfile.ZipFile(copy) as z, zipfile.ZipFile(fmu) as original:
        assert set(z.namelist()) == set(original.namelist()) | {f"resources/{START_VALUES_FILE}"}
        assert all(z.read(name) == original.read(name) for name in members)
