"""The FMUs the hostile campaign drives, prepared (fmus/hostile/cases.py): extracted once each,
picked by name, and told apart by their binary (parcosim's wrapper or not, by its exported
symbol) and their identity (native or not), on made-up FMUs whose binaries are compiled here
(issue 31: seed 3601's survivor [220], the check of the binary that only the slow campaign
ran)."""
from __future__ import annotations

import json
import subprocess
import zipfile

import fmpy
import pytest

from fmus.hostile import cases
from fmus.hostile.cases import extract_fmus, is_native, prepared_fmus, prepared_native_fmus, wrapper_is_ours
from fmus.slave.base import WRAPPER_SYMBOL
from fmus.slave.identity import IDENTITY_FILE
from tests.fmus.export.test_oracles_export import fake_fmu


def _binary(tmp_path, name: str, symbol: str) -> bytes:
    """A shared library exporting ``symbol``, compiled with the kernels' compiler."""
    from kernels import build

    try:
        compiler = build.compiler()
    except build.NoCompiler as exc:
        pytest.skip(f"no C compiler to make the FMUs' binaries: {exc}")
    source = tmp_path / f"{name}.c"
    source.write_text(f"int {symbol}(void) {{ return 1; }}\n")
    library = tmp_path / f"{name}.so"
    subprocess.run([compiler, "-shared", "-fPIC", str(source), "-o", str(library)], check=True)
    return library.read_bytes()


@pytest.fixture(scope="module")
def fmu_dir(tmp_path_factory):
    """Three FMUs: ``Ours`` with parcosim's wrapper symbol, ``Theirs`` without, and
    ``SpecPlant_delta3.fmu`` whose binary is named by its identifier ``SpecPlant`` (with the
    symbol), ``Theirs`` marked native in its identity."""
    tmp = tmp_path_factory.mktemp("hostile_fmus")
    folder = tmp / "fmus"
    folder.mkdir()
    for file, identifier, symbol, native in (("Ours", "Ours", WRAPPER_SYMBOL, False),
                                               ("Theirs", "Theirs", "fmi2DoStep", True),
                                               ("SpecPlant_delta3", "SpecPlant", WRAPPER_SYMBOL, False)):
        path = fake_fmu(folder / f"{file}.fmu", identifier)
        with zipfile.ZipFile(path, "a") as z:
            z.writestr(f"binaries/{fmpy.platform}/{identifier}.so", _binary(tmp, identifier, symbol))
            z.writestr(f"resources/{IDENTITY_FILE}", json.dumps({"model": identifier, "native": native}))
    return folder


def test_the_wrapper_is_told_by_the_symbol_of_the_binary_named_by_the_identifier(fmu_dir, tmp_path):
    """Catches the resources' folder (beside which the binaries are) built wrongly (seed 3601's
    [220]: a TypeError, a failed check read as "not ours"), the binary looked up by the file's
    name instead of the model identifier, or the answer inverted."""
    unzipped = prepared_fmus(fmu_dir, None, tmp_path)
    assert set(unzipped) == {"Ours", "Theirs", "SpecPlant_delta3"}
    assert {model: wrapper_is_ours(path, model) for model, path in unzipped.items()} == {
        "Ours": True, "Theirs": False, "SpecPlant_delta3": True}
    assert {model: is_native(path) for model, path in unzipped.items()} == {
        "Ours": False, "Theirs": True, "SpecPlant_delta3": False}
    assert is_native(tmp_path) is False                       # no identity at all


def test_models_are_picked_by_name_extracted_once_and_an_unknown_one_is_named(fmu_dir, tmp_path):
    """``models`` picks FMUs by file name; each is extracted under ``work/fmus/<model>`` once (a
    second preparation keeps the first extraction); an unknown name is a ValueError listing
    what there is."""
    unzipped = prepared_fmus(fmu_dir, "Theirs,Ours", tmp_path)
    assert unzipped == {"Theirs": tmp_path / "fmus" / "Theirs", "Ours": tmp_path / "fmus" / "Ours"}
    kept = unzipped["Ours"] / "kept.txt"
    kept.write_text("first extraction")
    assert extract_fmus({"Ours": fmu_dir / "Ours.fmu"}, tmp_path / "fmus") == {"Ours": unzipped["Ours"]}
    assert kept.read_text() == "first extraction"
    with pytest.raises(ValueError, match=r"no FMU \['Nope'\]; available: Ours, SpecPlant_delta3, Theirs"):
        prepared_fmus(fmu_dir, "Ours,Nope", tmp_path)


def test_the_native_fmus_are_those_of_the_folder_or_built_plus_the_loop_picked_and_sanitized(fmu_dir, tmp_path,
                                                                                             monkeypatch):
    """``prepared_native_fmus``: every FMU of ``fmu_dir`` (else ``build_native_all`` into
    ``work/native``), with ``loop_fmu`` as ``ClosedLoop``, ``models`` picking by name, each
    rebuilt by ``sanitized_from_sources`` into ``work/sanitized`` with ``sanitize`` (and
    taken as it is without), extracted under ``work/fmus``.  Catches the loop dropped or
    put under another name, the models' pick ignored, the sanitizer's rebuild skipped or
    done without asking, and the built FMUs taken from another folder."""
    import fmus.native.build

    sanitized, built = [], []

    def sanitize(path, out_dir):
        sanitized.append((path, out_dir))
        return path

    def build(out_dir):
        built.append(out_dir)
        return [fmu_dir / "Ours.fmu", fmu_dir / "Theirs.fmu"]

    monkeypatch.setattr(cases, "sanitized_from_sources", sanitize)
    monkeypatch.setattr(fmus.native.build, "build_native_all", build)
    loop = fmu_dir / "SpecPlant_delta3.fmu"
    unzipped = prepared_native_fmus(fmu_dir, "ClosedLoop,Theirs", tmp_path / "a", sanitize=True, loop_fmu=str(loop))
    assert unzipped == {"ClosedLoop": tmp_path / "a" / "fmus" / "ClosedLoop", "Theirs": tmp_path / "a" / "fmus" / "Theirs"}
    assert sanitized == [(loop, tmp_path / "a" / "sanitized"), (fmu_dir / "Theirs.fmu", tmp_path / "a" / "sanitized")]
    assert (unzipped["ClosedLoop"] / "binaries" / fmpy.platform / "SpecPlant.so").is_file()
    assert built == []
    unzipped = prepared_native_fmus(None, None, tmp_path / "b", sanitize=False)
    assert built == [tmp_path / "b" / "native"] and len(sanitized) == 2
    assert unzipped == {m: tmp_path / "b" / "fmus" / m for m in ("Ours", "Theirs")}
    with pytest.raises(ValueError, match=r"no FMU \['ClosedLoop'\]; available: Ours, SpecPlant_delta3, Theirs"):
        prepared_native_fmus(fmu_dir, "Ours,ClosedLoop", tmp_path / "c", sanitize=False)
