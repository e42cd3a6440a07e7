"""``fmus.export.archive.rewrite`` and ``umask_mode`` on zips written here, and what
``fmus.export.specfmu.build_plant_fmu`` asks of the build (recorded, not run): every member
kept with its own entry (compression, date, mode) unless replaced, added or left out (None), a
(ZipInfo, bytes) member's attributes honoured, the target replaced atomically with the umask's
mode and no temporary file left, also when the copy fails; the spec plant's script, class,
resource and options, and its two refusals (issue 31: rewrite ran only inside builds, where every
member is new or deflated; the spec FMU's refusals were never taken).  Fast."""
from __future__ import annotations

import os
import re
import stat
import zipfile

import pytest

from fmus.export import archive, specfmu
from fmus.export.archive import rewrite, umask_mode


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _source(path):
    with zipfile.ZipFile(path, "w") as z:
        stored = zipfile.ZipInfo("binaries/linux64/M.so", date_time=(2001, 2, 3, 4, 5, 6))
        stored.compress_type = zipfile.ZIP_STORED
        stored.external_attr = 0o755 << 16
        z.writestr(stored, b"\x7fELF binary")
        z.writestr("modelDescription.xml", b"<old/>", compress_type=zipfile.ZIP_DEFLATED)
        z.writestr("resources/gone.json", b"{}")
    return path


def test_members_are_replaced_added_or_left_out_and_the_others_keep_their_entries(tmp_path):
    """Catches a kept member recompressed, redated or its mode lost, a None member written
    (or the old one kept), a replaced member written twice, and a str member not encoded."""
    source = _source(tmp_path / "a.fmu")
    info = zipfile.ZipInfo("resources/new.bin", date_time=(2020, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_STORED
    info.external_attr = 0o644 << 16
    target = rewrite(source, tmp_path / "out" / "b.fmu", {"modelDescription.xml": "<new é/>", "resources/gone.json": None,
                                                           "resources/new.bin": (info, b"\x00\x01"),
                                                           "resources/added.txt": b"added"})
    assert target == tmp_path / "out" / "b.fmu"
    with zipfile.ZipFile(target) as z:
        entries = {i.filename: i for i in z.infolist()}
        assert [i.filename for i in z.infolist()] == ["binaries/linux64/M.so", "modelDescription.xml",
                                                      "resources/new.bin", "resources/added.txt"]
        assert z.read("modelDescription.xml") == "<new é/>".encode()
        assert z.read("binaries/linux64/M.so") == b"\x7fELF binary" and z.read("resources/new.bin") == b"\x00\x01"
    kept = entries["binaries/linux64/M.so"]
    assert (kept.compress_type, kept.date_time, kept.external_attr >> 16) == (zipfile.ZIP_STORED, (2001, 2, 3, 4, 5, 6),
                                                                             0o755)
    new = entries["resources/new.bin"]
    assert (new.compress_type, new.date_time, new.external_attr >> 16) == (zipfile.ZIP_STORED, (2020, 1, 1, 0, 0, 0),
                                                                          0o644)
    assert entries["resources/added.txt"].compress_type == zipfile.ZIP_DEFLATED     # the default: deflated
    with zipfile.ZipFile(source) as z:                                             # the source as it was
        assert z.read("modelDescription.xml") == b"<old/>" and "resources/gone.json" in z.namelist()


def test_in_place_the_file_is_replaced_with_the_umasks_mode_and_nothing_else_is_left(tmp_path):
    """mkstemp makes 0600: the package must get what ``open`` would give.  Catches the chmod
    dropped, the temporary file left beside the target, and the source read after it was
    replaced."""
    source = _source(tmp_path / "a.fmu")
    os.chmod(source, 0o600)
    rewrite(source, source, {"resources/added.txt": "x"})
    assert stat.S_IMODE(os.stat(source).st_mode) == 0o666 & ~_umask() == umask_mode()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.fmu"]
    with zipfile.ZipFile(source) as z:
        assert sorted(z.namelist()) == ["binaries/linux64/M.so", "modelDescription.xml", "resources/added.txt",
                                        "resources/gone.json"]


def test_a_failed_copy_raises_leaves_the_target_alone_and_no_temporary_file(tmp_path):
    (tmp_path / "not.zip").write_bytes(b"not a zip")
    target = tmp_path / "t.fmu"
    target.write_bytes(b"old target")
    with pytest.raises(zipfile.BadZipFile):
        rewrite(tmp_path / "not.zip", target, {"a": b"b"})
    assert target.read_bytes() == b"old target"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["not.zip", "t.fmu"]


def test_the_copy_is_a_hidden_temporary_beside_the_target_named_after_it_then_renamed(tmp_path, monkeypatch):
    """The target appears whole or not at all: the copy is written to ``.<target name>.<random>.tmp``
    in the target's folder (hidden, and a killed write's leftover names its target), then renamed
    onto it. Catches the temporary written elsewhere (a rename across file systems fails) or
    named otherwise."""
    source = _source(tmp_path / "a.fmu")
    moves, replace = [], os.replace

    def spy(src, dst):
        moves.append((os.fspath(src), os.fspath(dst)))
        return replace(src, dst)

    monkeypatch.setattr(archive.os, "replace", spy)
    target = rewrite(source, tmp_path / "out" / "b.fmu", {"resources/added.txt": "x"})
    [(temporary, renamed)] = moves
    assert renamed == os.fspath(target) and os.path.dirname(temporary) == os.fspath(target.parent)
    assert re.fullmatch(r"\.b\.fmu\.[A-Za-z0-9_]+\.tmp", os.path.basename(temporary)), temporary


def test_without_proc_the_umask_is_read_by_setting_it_and_put_back(monkeypatch):
    """Catches the fallback's mask inverted, another base than 0o666, or the umask left at 0o022."""
    before = _umask()
    try:
        os.umask(0o027)

        def no_proc(*args, **kwargs):
            raise OSError("no /proc")
        monkeypatch.setattr(archive, "open", no_proc, raising=False)
        assert archive.umask_mode() == 0o640
        assert _umask() == 0o027
    finally:
        os.umask(before)


def test_the_spec_plant_is_built_from_its_slave_with_the_checked_spec_as_its_resource(monkeypatch, tmp_path):
    """Catches another script or class, the spec's text not the checked one or under another
    resource name, the variable-step flag or the state options not passed."""
    from fmus.export.build import ROOT
    from fmus.slave.designs import SPEC_RESOURCE
    from plant.spec import load, spec_path

    made = []

    def build_bundled_fmu(script, model, path, resources=(), **options):
        made.append((script, model, path, {r.name: r.read_text(encoding="utf-8") for r in resources}, options))
        return path
    monkeypatch.setattr(specfmu, "build_bundled_fmu", build_bundled_fmu)
    out = tmp_path / "p.fmu"
    assert specfmu.build_plant_fmu("bench_5r", out) == out
    ((script, model, path, resources, options),) = made
    assert (script, model, path) == (ROOT / "fmus" / "slaves" / "parcosim_specplant.py", "SpecPlant", out)
    assert script.is_file()
    assert resources == {SPEC_RESOURCE: load(spec_path("bench_5r")).text}
    assert options == {"canHandleVariableCommunicationStepSize": "true", "canGetAndSetFMUstate": "true",
                       "canSerializeFMUstate": "true"}


def test_a_serial_chain_or_an_output_not_ending_in_fmu_is_refused_naming_it(monkeypatch, tmp_path):
    from plant.spec import spec_path

    monkeypatch.setattr(specfmu, "build_bundled_fmu", lambda *a, **k: pytest.fail("built"))
    with pytest.raises(ValueError) as refused:
        specfmu.build_plant_fmu("rr", tmp_path / "rr.fmu")
    assert str(refused.value) == f"{spec_path('rr')}: a serial chain (no [platform]) cannot be built as a plant FMU"
    with pytest.raises(ValueError) as refused:
        specfmu.build_plant_fmu("bench_5r", tmp_path / "p.FMU.zip")
    assert str(refused.value) == f"output {str(tmp_path / 'p.FMU.zip')!r} must end in .fmu"
