"""What ``fmus.export.wrapper`` reads from and writes into an FMU, on made-up FMUs (nothing is
compiled: the compiled wrapper is a stand-in file): the co-simulation modelIdentifier, or a
refusal naming the FMU; the identity the wrapper checks (the carried one with the model
description's GUID and identifier); the wrapper installed as the binary named by the
identifier, executable and compressed, or only the identity without a compiler; and whether
an FMU's binary is the wrapper (issue 31: these ran only inside full builds, where the
identifier, the file's name and the model's name are all the same)."""
from __future__ import annotations

import json
import stat
import xml.etree.ElementTree as ET
import zipfile

import pytest

from fmus.export import wrapper
from fmus.export.wrapper import PLATFORM, VERSION_SYMBOL, has_wrapper, identity, install_wrapper, model_identifier
from fmus.slave.identity import IDENTITY_FILE
from tests.fmus.export.test_oracles_export import fake_fmu


def _md_fmu(path, cosimulation):
    """An FMU holding only a model description with ``cosimulation``'s attributes (None: no
    CoSimulation element)."""
    root = ET.Element("fmiModelDescription", fmiVersion="2.0", modelName="M", guid="{g}")
    if cosimulation is not None:
        ET.SubElement(root, "CoSimulation", **cosimulation)
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("modelDescription.xml", ET.tostring(root))
    return path


@pytest.mark.parametrize("cosimulation", [None, {}, {"modelIdentifier": ""}])
def test_an_fmu_without_a_cosimulation_identifier_is_refused_naming_it(tmp_path, cosimulation):
    """Catches a missing CoSimulation element or identifier taken as a binary named "None"
    or "" (or a crash on None)."""
    fmu = _md_fmu(tmp_path / "x.fmu", cosimulation)
    with pytest.raises(ValueError) as refused:
        model_identifier(fmu)
    assert str(refused.value) == f"{fmu}: no co-simulation modelIdentifier in modelDescription.xml"


def test_the_identity_is_the_carried_one_with_the_guid_and_identifier_of_the_description(tmp_path):
    """The file is named File, its identifier Ident: the identifier, not the file's or the
    model's name; the description's GUID wins over a carried one; without a carried
    identity, only the two.  Catches the carried identity lost or winning, the file's name
    taken for the identifier."""
    fmu = _md_fmu(tmp_path / "File.fmu", {"modelIdentifier": "Ident"})
    assert model_identifier(fmu) == "Ident"
    assert identity(fmu) == {"guid": "{g}", "model_identifier": "Ident"}
    with zipfile.ZipFile(fmu, "a") as z:
        z.writestr(f"resources/{IDENTITY_FILE}", json.dumps({"model": "M", "package": "p", "guid": "{old}"}))
    assert identity(fmu) == {"model": "M", "package": "p", "guid": "{g}", "model_identifier": "Ident"}


def test_the_wrapper_goes_in_as_the_executable_binary_of_the_identifier_with_the_identity(tmp_path, monkeypatch):
    """Catches the binary written under another name or platform, not executable or stored
    uncompressed, the identity not written (or not the one :func:`identity` reads), the
    FMU's other members lost, and the answer (True) wrong."""
    stand_in = tmp_path / "wrapper.so"
    stand_in.write_bytes(b"\x7fELF..." + VERSION_SYMBOL.encode() + b"..." * 100)
    monkeypatch.setattr(wrapper, "compiled_wrapper", lambda quiet=False: stand_in)
    fmu = fake_fmu(tmp_path / "Drive.fmu", "Ident")
    expected_identity = identity(fmu)
    assert not has_wrapper(fmu)
    assert install_wrapper(fmu) is True
    with zipfile.ZipFile(fmu) as z:
        names = set(z.namelist())
        info = z.getinfo(f"binaries/{PLATFORM}/Ident.so")
        assert z.read(info) == stand_in.read_bytes()
        assert stat.S_IMODE(info.external_attr >> 16) == 0o755 and info.compress_type == zipfile.ZIP_DEFLATED
        assert z.read(f"resources/{IDENTITY_FILE}").decode() == json.dumps(expected_identity) + "\n"
    assert names == {"modelDescription.xml", f"binaries/{PLATFORM}/Ident.so", f"resources/{IDENTITY_FILE}"}
    assert has_wrapper(fmu)


def test_without_a_compiler_only_the_identity_goes_in(tmp_path, monkeypatch):
    """Catches a binary written (or an error) when there is no wrapper to install, the
    identity then left out, and the answer (False) wrong; a binary that is not the wrapper
    is told apart from one that is."""
    monkeypatch.setattr(wrapper, "compiled_wrapper", lambda quiet=False: None)
    fmu = fake_fmu(tmp_path / "Drive.fmu", "Ident")
    assert install_wrapper(fmu) is False
    with zipfile.ZipFile(fmu) as z:
        assert set(z.namelist()) == {"modelDescription.xml", f"resources/{IDENTITY_FILE}"}
        assert json.loads(z.read(f"resources/{IDENTITY_FILE}")) == {"guid": "{0}", "model_identifier": "Ident"}
    with zipfile.ZipFile(fmu, "a") as z:
        z.writestr(f"binaries/{PLATFORM}/Ident.so", b"\x7fELF pythonfmu's binary")
        z.writestr(f"binaries/{PLATFORM}/Drive.so", VERSION_SYMBOL.encode())     # the file's name: not looked at
    assert not has_wrapper(fmu)
