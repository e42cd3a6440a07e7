"""The copy of a package that libcosim loads (fmus.ssp.libcosim.with_libcosim_annotation) read
back: the OSP annotation holds the step and the worker threads asked for (by default the
package's own communication step), once, and every other member and element is the package's
(issue 31: seed 3601's survivor [24]; every written value read back exactly).  The FMUs are
model descriptions only (test_oracles_export.py's): nothing is built or run, no libcosim
needed."""
from __future__ import annotations

import xml.etree.ElementTree as ET
import zipfile

import pytest

from fmus.cosim.system import Component, Connection, System
from fmus.ssp.export import NS, OSP_ANNOTATION, export_ssp, read_ssp_experiment, read_ssp_parameters
from fmus.ssp.libcosim import read_libcosim_step, with_libcosim_annotation
from tests.fmus.export.test_oracles_export import fake_fmu

STEP = 1e-3 / 3.0       # no short decimal: written and read back to the last bit


@pytest.fixture
def package(tmp_path):
    fmus = {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}
    system = System((Component("first", "Alpha", {"gain": 1.5}), Component("second", "Beta", {"count": 7})),
                    (Connection("first.y", "second.u"),), ("second.y",), stop_time=0.7, step=STEP)
    return export_ssp(system, tmp_path / "sys.ssp", fmus=fmus)


def _members(path) -> dict:
    with zipfile.ZipFile(path) as z:
        return {name: z.read(name) for name in z.namelist()}


def _without_osp(ssd: bytes) -> bytes:
    """The SSD with its OSP annotations removed, canonical (what must stay as it was)."""
    root = ET.fromstring(ssd)
    for annotations in root.iterfind("ssd:DefaultExperiment/ssd:Annotations", NS):
        for annotation in annotations.findall("ssc:Annotation", NS):
            if annotation.get("type") == OSP_ANNOTATION:
                annotations.remove(annotation)
    return ET.canonicalize(ET.tostring(root), strip_text=True).encode()


@pytest.mark.parametrize("step, threads, expected", [(None, None, (STEP, None)), (None, 3, (STEP, 3)),
                                                     (2e-3 / 7.0, 0, (2e-3 / 7.0, 0)), (5e-3, None, (5e-3, None))])
@pytest.mark.parametrize("as_package", [True, False])
def test_the_annotation_holds_the_step_and_threads_asked_for_and_nothing_else_changes(package, tmp_path, step, threads,
                                                                                       expected, as_package):
    """Catches a step given being replaced by the package's (seed 3601's [24]: ``step is not
    None``), the package's step not taken by default, the threads lost, a second OSP annotation
    added beside the export's, and any other member or element changed (as a package and
    unpacked into a folder)."""
    assert read_libcosim_step(package) == (STEP, 0)        # export_ssp writes one: the calling thread
    out = with_libcosim_annotation(package, tmp_path / ("copy.ssp" if as_package else "copy"), step, threads)
    if as_package:
        copied = _members(out)
        assert read_libcosim_step(out) == expected
    else:
        copied = {p.relative_to(out).as_posix(): p.read_bytes() for p in out.rglob("*") if p.is_file()}
        from fmus.ssp.libcosim import _osp_step

        assert _osp_step(ET.fromstring(copied["SystemStructure.ssd"])) == expected
    original = _members(package)
    assert set(copied) == set(original)
    assert all(copied[name] == data for name, data in original.items() if name != "SystemStructure.ssd")
    assert _without_osp(copied["SystemStructure.ssd"]) == _without_osp(original["SystemStructure.ssd"])
    assert copied["SystemStructure.ssd"].count(b"FixedStepAlgorithm") == 1
    if as_package:
        assert read_ssp_experiment(out) == read_ssp_experiment(package)
        assert read_ssp_parameters(out) == read_ssp_parameters(package) == {"first.gain": 1.5, "second.count": 7}


def test_a_package_without_a_communication_step_needs_one_given(tmp_path, package):
    """No step in the package and none given: a ValueError naming the package, no file."""
    ssd = ET.fromstring(_members(package)["SystemStructure.ssd"])
    ssd.remove(ssd.find("ssd:DefaultExperiment", NS))
    from fmus.export.archive import rewrite

    bare = rewrite(package, tmp_path / "bare.ssp", {"SystemStructure.ssd": ET.tostring(ssd)})
    assert read_ssp_experiment(bare) == (None, None, None)
    with pytest.raises(ValueError, match=f"{bare}: the package gives no communication step; pass step"):
        with_libcosim_annotation(bare, tmp_path / "out.ssp")
    assert not (tmp_path / "out.ssp").exists()
    out = with_libcosim_annotation(bare, tmp_path / "given.ssp", step=4e-3, worker_threads=1)
    assert read_libcosim_step(out) == (4e-3, 1)


def test_a_package_without_a_system_structure_is_named(tmp_path):
    """Catches the missing SystemStructure.ssd surfacing as a KeyError of zipfile."""
    empty = tmp_path / "empty.ssp"
    with zipfile.ZipFile(empty, "w") as z:
        z.writestr("resources/x.txt", "x")
    with pytest.raises(ValueError, match=f"{empty}: no SystemStructure.ssd"):
        read_libcosim_step(empty)


def test_a_log_level_is_one_of_libcosims_and_warn_is_warning():
    """Catches an unknown level passed on to libcosim, or the alias "warn" (Ecos' word) refused."""
    from fmus.ssp.libcosim import libcosim_available, set_libcosim_log_level

    if libcosim_available() is not None:
        pytest.skip(f"libcosimpy cannot be loaded ({libcosim_available()})")
    with pytest.raises(ValueError, match=r"log level 'verbose': one of trace, debug, info, warning, error, fatal"):
        set_libcosim_log_level("verbose")
    set_libcosim_log_level("WARN")
    set_libcosim_log_level("warning")


def test_the_experiment_takes_parcosims_step_first_and_libcosims_without_it(tmp_path, package):
    """A package whose only step is libcosim's annotation (as another tool writes it) gives
    that step; with both, parcosim's own wins whatever libcosim's says; without a stop time
    the stop is None.  Catches the OSP annotation not read, read first, or the times
    swapped."""
    from fmus.export.archive import rewrite
    from fmus.ssp.export import STEP_ANNOTATION

    start, stop, step = read_ssp_experiment(package)
    assert step == STEP and stop is not None and start is not None
    other = with_libcosim_annotation(package, tmp_path / "other.ssp", 5e-4, None)
    assert read_ssp_experiment(other) == (start, stop, STEP)
    ssd = ET.fromstring(_members(other)["SystemStructure.ssd"])
    experiment = ssd.find("ssd:DefaultExperiment", NS)
    for annotation in experiment.iterfind("ssd:Annotations/ssc:Annotation", NS):
        if annotation.get("type") == STEP_ANNOTATION:
            experiment.find("ssd:Annotations", NS).remove(annotation)
    del experiment.attrib["stopTime"]
    osp_only = rewrite(other, tmp_path / "osp.ssp", {"SystemStructure.ssd": ET.tostring(ssd)})
    assert read_ssp_experiment(osp_only) == (start, None, 5e-4)
