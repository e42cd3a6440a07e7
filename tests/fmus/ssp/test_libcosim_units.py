"""The record fmus/ssp/libcosim.py makes of a step libcosim refused (``_refusal``), and the
annotated copy's destination (``with_libcosim_annotation``): units without running libcosim.

``_refusal`` reads each component's String output ``refusal`` through a last-value observer;
the observer here is a stand-in (libcosimpy's hands ``c_char_p`` values: bytes or None; a
``str`` is taken as it is) so that every kind of value is checked, not only those one FMU
happens to produce.
"""
from __future__ import annotations

from types import SimpleNamespace

import pytest

pytest.importorskip("libcosimpy")

from libcosimpy.CosimEnums import CosimVariableType  # noqa: E402

from fmus.ssp import libcosim  # noqa: E402
from fmus.status import RunError, RunStatus  # noqa: E402

#: A component's refusal record, as its String output holds it.
RECORD = RunError(RunStatus.REFUSED, "input q1 = nan is not finite", instance="ctrl", time=0.25)


class Observer:
    """A last-value observer whose String values are ``values`` (slave index -> value)."""

    def __init__(self, values):
        self.values = values

    def last_string_values(self, index, references):
        assert references == [7]
        return [self.values[index]]


def refusal(monkeypatch, values, message="step failed"):
    """``_refusal`` of two components, ``a`` (index 0) and ``ctrl`` (index 1), whose outputs
    ``refusal`` (reference 7) hold ``values``."""
    from libcosimpy import CosimObserver as module

    monkeypatch.setattr(module.CosimObserver, "create_last_value", staticmethod(lambda: Observer(values)))
    string = SimpleNamespace(type=CosimVariableType.STRING.value, reference=7)
    variables = {"a": {"refusal": string}, "ctrl": {"refusal": string}}
    execution = SimpleNamespace(add_observer=lambda observer: True)
    return libcosim._refusal(execution, {"ctrl": 1, "a": 0}, variables, 0.25, message)


@pytest.mark.parametrize("text", [RECORD.to_json(), RECORD.to_json().encode()])
def test_a_components_refusal_text_is_the_record_whether_bytes_or_str(text, monkeypatch):
    """The first component (by index) whose refusal is not empty names the record: its
    message, instance and time, as bytes (libcosimpy) or as str."""
    error = refusal(monkeypatch, {0: None, 1: text})
    assert error.instance == "ctrl" and error.time == 0.25 and "input q1 = nan is not finite" in str(error)
    assert error.kind is RunStatus.REFUSED


@pytest.mark.parametrize("empty", [None, "", b""])
def test_without_a_refusal_text_libcosims_message_is_the_record(empty, monkeypatch):
    """No component says why (None, "" or b""): libcosim's message and the step's time."""
    error = refusal(monkeypatch, {0: empty, 1: empty}, message=" the slave failed \n")
    assert error.instance is None
    assert str(error) == "libcosim stopped at the step from t = 0.25 s: the slave failed"


def minimal_package(path):
    """A package of one SystemStructure.ssd (no default experiment) and one other file."""
    import zipfile

    from fmus.ssp.export import NS

    ssd = (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssd:SystemStructureDescription xmlns:ssd="{NS["ssd"]}" '
           f'xmlns:ssc="{NS["ssc"]}" version="1.0" name="s"><ssd:System name="root"/>'
           '</ssd:SystemStructureDescription>\n')
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("SystemStructure.ssd", ssd)
        zf.writestr("resources/a.fmu", b"not really an FMU")
    return path


@pytest.mark.parametrize("name", ["copy.ssp", "copy.SSP", "unpacked"])
def test_the_annotated_copy_is_written_at_out_and_the_package_is_left_as_it_was(name, tmp_path):
    """``out`` (a package for .ssp in any case, else a directory) holds the annotation with the
    given step and threads and every file of the package; the package itself is unchanged."""
    import zipfile

    source = minimal_package(tmp_path / "source.ssp")
    before = source.read_bytes()
    out = libcosim.with_libcosim_annotation(source, tmp_path / name, step=2e-3, worker_threads=3)
    assert out == tmp_path / name and source.read_bytes() == before
    assert libcosim.read_libcosim_step(source) == (None, None)
    if out.is_dir():
        assert (out / "resources" / "a.fmu").read_bytes() == b"not really an FMU"
        with zipfile.ZipFile(tmp_path / "check.ssp", "w") as zf:     # read it back as read_libcosim_step reads
            zf.writestr("SystemStructure.ssd", (out / "SystemStructure.ssd").read_bytes())
        assert libcosim.read_libcosim_step(tmp_path / "check.ssp") == (2e-3, 3)
    else:
        assert zipfile.is_zipfile(out)
        with zipfile.ZipFile(out) as zf:
            assert sorted(zf.namelist()) == ["SystemStructure.ssd", "resources/a.fmu"]
        assert libcosim.read_libcosim_step(out) == (2e-3, 3)


def test_an_annotated_copy_without_a_step_is_refused_when_the_package_gives_none(tmp_path):
    """No step passed and none in the package's default experiment: ValueError naming the package."""
    source = minimal_package(tmp_path / "source.ssp")
    with pytest.raises(ValueError, match="gives no communication step; pass step"):
        libcosim.with_libcosim_annotation(source, tmp_path / "out.ssp")
    assert not (tmp_path / "out.ssp").exists()
