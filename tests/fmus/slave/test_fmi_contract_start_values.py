"""Start values from an FMU's resources (``resources/start_values.json``, written by
fmus.systemfmu.export.with_start_values for an SSP package's baked copies) read back by the slave
at instantiation, and the slave's instantiation leaving ``sys.path`` without the duplicates
pythonfmu adds (fmus/slave/base.py; issue 31: every exported value read back exactly, by the
code that reads it).  In process: fast."""
from __future__ import annotations

import json
import sys

from fmus.slave.base import START_VALUES_FILE
from fmus.slaves.parcosim_trajectory import Trajectory


def test_the_start_values_file_gives_each_declared_variable_its_value_and_nothing_else(tmp_path):
    """Catches the file not read, read from elsewhere than the resources, values of undeclared
    names set as attributes, or the declared start kept over the file's."""
    values = {"kind": "triangle", "side_time": 0.1 + 0.2, "cycles": 2 ** 31 - 1, "not_a_variable": 5.0}
    (tmp_path / START_VALUES_FILE).write_text(json.dumps(values))
    slave = Trajectory(instance_name="t", resources=str(tmp_path))
    assert (slave.kind, slave.side_time, slave.cycles) == ("triangle", 0.1 + 0.2, 2 ** 31 - 1)
    assert not hasattr(slave, "not_a_variable")
    plain = Trajectory(instance_name="t", resources=str(tmp_path / "elsewhere"))
    default = Trajectory(instance_name="t")
    assert (plain.kind, plain.side_time, plain.cycles) == (default.kind, default.side_time, default.cycles) == (
        "circle", 0.75, -1)


def test_an_instantiation_leaves_no_duplicate_on_sys_path(monkeypatch, tmp_path):
    """pythonfmu puts the resources on sys.path at every instantiation: the slave drops the
    repeated entries, keeping the first of each in its place."""
    path = ["/a", str(tmp_path), "/b", "/a", str(tmp_path), "/c", "/b"]
    monkeypatch.setattr(sys, "path", list(path))
    Trajectory(instance_name="t", resources=str(tmp_path))
    assert sys.path == ["/a", str(tmp_path), "/b", "/c"]
