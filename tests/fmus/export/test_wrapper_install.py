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
import warnings
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



def test_the_wrapper_entry_is_dated_at_a_fixed_midnight_whenever_it_is_installed(tmp_path, monkeypatch):
    """The binary's zip entry does not carry the install time: installed at two different
    clock times, the two entries are the same to the byte in date and content, dated
    2020-01-01 00:00:00 (exactly: the zip's 2-second resolution keeps a midnight as it is).
    Catches the date taken from the clock, or any field of the fixed date changed (seed 4001's
    survivor [29], the hour 0 made 1)."""
    import time

    stand_in = tmp_path / "wrapper.so"
    stand_in.write_bytes(b"\x7fELF..." + VERSION_SYMBOL.encode())
    monkeypatch.setattr(wrapper, "compiled_wrapper", lambda quiet=False: stand_in)
    entries = []
    for k, now in enumerate((1.0e9, 1.7e9 + 3601.0)):
        monkeypatch.setattr(time, "time", lambda now=now: now)
        fmu = fake_fmu(tmp_path / f"Drive{k}.fmu", "Ident")
        install_wrapper(fmu)
        with zipfile.ZipFile(fmu) as z:
            info = z.getinfo(f"binaries/{PLATFORM}/Ident.so")
            entries.append((info.date_time, info.external_attr, z.read(info)))
    assert entries[0] == entries[1]
    assert entries[0][0] == (2020, 1, 1, 0, 0, 0)

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


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A cache folder of its own (``$PARCOSIM_CACHE``), and a C compiler or a skip."""
    if wrapper.compiler() is None:
        pytest.skip("no C compiler")
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache" / "fmi2-wrapper"


def test_the_wrapper_is_compiled_once_per_source_and_kept_under_its_key(cache, tmp_path, monkeypatch):
    """The wrapper is compiled into the cache as ``parcosim_fmi2-<key>.so`` (the key: a hash
    of the source, the flags, the compiler and Python), taken from there the next time
    without compiling, and compiled anew, beside the old one, when the source changes.
    Catches the cache's file not named by its key (a stale wrapper kept after its source
    changed), the cache not used, and a compiled file that is not the wrapper."""
    first = wrapper.compiled_wrapper()
    assert first == cache / f"parcosim_fmi2-{wrapper._key(wrapper.compiler())}.so" and first.is_file()
    assert VERSION_SYMBOL.encode() in first.read_bytes()
    monkeypatch.setattr(wrapper.subprocess, "run", lambda *a, **k: pytest.fail("compiled again"))
    assert wrapper.compiled_wrapper() == first
    monkeypatch.undo()
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path / "cache"))
    changed = tmp_path / "parcosim_fmi2.c"
    changed.write_bytes(wrapper.SOURCE.read_bytes() + b"\n/* changed */\n")
    monkeypatch.setattr(wrapper, "SOURCE", changed)
    second = wrapper.compiled_wrapper()
    assert second != first and second.parent == cache and first.is_file() and second.is_file()
    assert sorted(p.name for p in cache.iterdir()) == sorted([first.name, second.name])


def test_a_source_the_compiler_refuses_is_an_error_naming_the_command_and_leaves_nothing(cache, tmp_path,
                                                                                      monkeypatch):
    """Catches a failed compilation taken as no compiler (None), leaving a file in the cache, or its
    message without the compiler's own diagnostic (its output not captured: the line after the command
    names the broken file's line 1)."""
    broken = tmp_path / "broken.c"
    broken.write_text("this is not C\n")
    monkeypatch.setattr(wrapper, "SOURCE", broken)
    with pytest.raises(wrapper.WrapperBuildError) as failed:
        wrapper.compiled_wrapper()
    assert str(failed.value).startswith("compiling the FMI wrapper failed (") and str(broken) in str(failed.value)
    command, diagnostic = str(failed.value).split("):\n", 1)
    assert str(broken) in command and f"{broken}:1:" in diagnostic, diagnostic
    assert list(cache.iterdir()) == []


def test_without_python_headers_there_is_no_wrapper_and_one_warning_saying_why(cache, tmp_path, monkeypatch):
    """Catches the headers' check inverted, the reason not named, the warning repeated or
    given with ``quiet``."""
    monkeypatch.setattr(wrapper, "_include_dir", lambda: str(tmp_path))
    monkeypatch.setattr(wrapper, "_warned", False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert wrapper.compiled_wrapper(quiet=True) is None
        assert caught == []
        assert wrapper.compiled_wrapper() is None and wrapper.compiled_wrapper() is None
    assert [str(w.message) for w in caught] == [
        f"parcosim's FMI wrapper not compiled: no Python.h in {tmp_path} (install the Python development headers); "
        "the FMUs keep pythonfmu 0.7's wrapper, which crashes the importer on some inputs (docs/extremes.md, "
        "'The FMI wrapper')"]
    assert caught[0].category is RuntimeWarning and not cache.exists()
