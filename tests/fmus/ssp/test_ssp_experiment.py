"""What the SSP runners read from a package before they run it (fmus/ssp/run.py): the stop time
and step (the package's, or the caller's), refused when neither gives one or the step is not
> 0, and fmpy's parameter set, each binding typed as exported (issue 31: every exported value
read back exactly; fmpy would read the XML string "false" as True).  The FMUs are model
descriptions only: nothing is built or run."""
from __future__ import annotations

import xml.etree.ElementTree as ET
import zipfile

import pytest

from fmus.cosim.system import Component, System
from fmus.export.archive import rewrite
from fmus.ssp.export import NS, PARAMETER_SET, export_ssp
from fmus.ssp.run import _experiment, fmpy_parameter_set
from tests.fmus.export.test_oracles_export import AWKWARD, TYPES, fake_fmu

STOP, STEP = 0.1 + 0.7, 1e-3 / 3.0


@pytest.fixture
def package(tmp_path):
    fmu = fake_fmu(tmp_path / "Alpha.fmu", "Alpha")
    system = System((Component("a", "Alpha", dict(AWKWARD)),), (), ("a.y",), stop_time=STOP, step=STEP)
    return export_ssp(system, tmp_path / "sys.ssp", fmus={"Alpha": fmu})


def test_the_experiment_is_the_packages_unless_given(package):
    """Catches the package's stop time or step not read, or the caller's not taking precedence."""
    assert _experiment(package, None, None) == (STOP, STEP)
    assert _experiment(package, 0.25, None) == (0.25, STEP)
    assert _experiment(package, None, 2e-3) == (STOP, 2e-3)
    for step in (0.0, -STEP):
        with pytest.raises(ValueError, match=rf"step_size = {step!r} must be > 0"):
            _experiment(package, None, step)


def test_a_package_without_an_experiment_needs_both_given(package, tmp_path):
    with zipfile.ZipFile(package) as z:
        ssd = ET.fromstring(z.read("SystemStructure.ssd"))
    ssd.remove(ssd.find("ssd:DefaultExperiment", NS))
    bare = rewrite(package, tmp_path / "bare.ssp", {"SystemStructure.ssd": ET.tostring(ssd)})
    for stop, step in ((None, None), (1.0, None), (None, 1e-3)):
        with pytest.raises(ValueError, match=f"{bare}: give stop_time and step_size"):
            _experiment(bare, stop, step)
    assert _experiment(bare, 1.0, 1e-3) == (1.0, 1e-3)


def test_fmpys_parameter_set_holds_every_binding_with_its_type_and_value(package):
    """Catches a value passed as its XML text (a Boolean "false" that fmpy takes for True), a
    type named otherwise than the FMU's variable, or the set named otherwise than the one
    the package's components bind."""
    pset = fmpy_parameter_set(package)
    assert pset.name == PARAMETER_SET
    got = {p.name: (p.type, p.value) for p in pset.parameters}
    assert got == {f"a.{name}": (TYPES[name], value) for name, value in AWKWARD.items()}
    assert all(type(value) is type(AWKWARD[name[2:]]) for name, (_, value) in got.items())
