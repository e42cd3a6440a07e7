"""The SSP package ``export_ssp`` writes, read back element by element with every attribute
compared exactly against SSP 1.0 and the system (issue 31: attributes that no tool here reads,
a component's type and implementation, the binding's type, the experiment's start, the
documents' versions, were never compared): SystemStructure.ssd, each ``.ssv`` and the archive's
members (names, compression, file mode).  FMUs made of a model description only
(test_oracles_export.py's): nothing is built."""
from __future__ import annotations

import os
import re
import stat
import xml.etree.ElementTree as ET
import zipfile

import pytest

from fmus.cosim.system import Component, Connection, System
from fmus.ssp import export as export_module
from fmus.ssp.export import (LIBCOSIM_WORKER_THREADS, NS, OSP_ANNOTATION, OSP_NS, PARAMETER_SET, STEP_ANNOTATION,
                             export_ssp)
from tests.fmus.export.test_oracles_export import fake_fmu

SSD, SSC, SSV = (f"{{{NS[p]}}}" for p in ("ssd", "ssc", "ssv"))
STEP = 1e-3 / 3.0
STOP = 0.1 + 0.7


def _system():
    return System((Component("first", "Alpha", {"gain": 1.5, "count": 3}), Component("second", "Beta"),
                   Component("third", "Alpha", {"flag": True, "label": "x"})),
                  (Connection("first.y", "second.u"), Connection("second.y", "third.u")), ("third.y",),
                  stop_time=STOP, step=STEP)


@pytest.fixture(params=[False, True], ids=["per-model", "baked"])
def package(request, tmp_path):
    fmus = {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}
    path = export_ssp(_system(), tmp_path / "out" / "Loop.ssp", fmus=fmus, bake=request.param)
    with zipfile.ZipFile(path) as z:
        return request.param, path, {i.filename: i for i in z.infolist()}, \
            {n: z.read(n) for n in z.namelist()}


def test_the_root_system_and_experiment_carry_exactly_their_attributes(package):
    """SSP 1.0: version 1.0, the system named by the file's stem, start time 0, the stop time
    and the step exactly (repr), the step in both annotations and libcosim's worker threads.
    Catches the start time, a version, the generation tool or the system's description
    changed, and the step or stop time rounded."""
    _, _, _, data = package
    root = ET.fromstring(data["SystemStructure.ssd"])
    assert root.tag == f"{SSD}SystemStructureDescription"
    assert root.attrib == {"version": "1.0", "name": "Loop", "generationTool": "parcosim (fmus.ssp.export.export_ssp)"}
    assert [child.tag for child in root] == [f"{SSD}System", f"{SSD}DefaultExperiment"]
    system = root.find(f"{SSD}System")
    assert system.attrib == {"name": "Loop",
                             "description": f"parcosim system, 3 components, communication step {STEP!r} s"}
    experiment = root.find(f"{SSD}DefaultExperiment")
    assert experiment.attrib == {"startTime": "0.0", "stopTime": repr(STOP)}
    (annotations,) = list(experiment)
    ours, osp = list(annotations)
    assert (ours.tag, ours.attrib) == (f"{SSC}Annotation", {"type": STEP_ANNOTATION})
    assert [(c.tag, c.attrib) for c in ours] == [("{urn:parcosim:ssp}CommunicationStep", {"value": repr(STEP)})]
    assert (osp.tag, osp.attrib) == (f"{SSC}Annotation", {"type": OSP_ANNOTATION})
    (algorithm,) = list(osp)
    assert [(c.tag, c.attrib) for c in algorithm] == [
        (f"{{{OSP_NS}}}FixedStepAlgorithm", {"baseStepSize": repr(STEP),
                                            "numWorkerThreads": str(LIBCOSIM_WORKER_THREADS)})]
    assert LIBCOSIM_WORKER_THREADS == 0


def test_each_component_is_a_cosimulation_fmu_with_its_source_and_binding(package):
    """SSP 1.0's MIME types: ``application/x-fmu-sharedlibrary`` for an FMU component,
    ``application/x-ssp-parameter-set`` for a binding.  Catches a component's type,
    implementation or source (its own copy when baked, its model's FMU when not) changed, a
    binding given to a component without values or pointing at another's file."""
    baked, _, _, data = package
    elements = ET.fromstring(data["SystemStructure.ssd"]).find(f"{SSD}System/{SSD}Elements")
    expected_source = {"first": "first" if baked else "Alpha", "second": "second" if baked else "Beta",
                       "third": "third" if baked else "Alpha"}
    assert [c.get("name") for c in elements] == ["first", "second", "third"]
    for component in elements:
        name = component.get("name")
        assert component.attrib == {"name": name, "type": "application/x-fmu-sharedlibrary",
                                    "source": f"resources/{expected_source[name]}.fmu",
                                    "implementation": "CoSimulation"}
        bindings = component.findall(f"{SSD}ParameterBindings/{SSD}ParameterBinding")
        if name == "second":
            assert bindings == [] and component.find(f"{SSD}ParameterBindings") is None
        else:
            assert [b.attrib for b in bindings] == [{"type": "application/x-ssp-parameter-set",
                                                     "source": f"resources/{name}.ssv"}]


def test_the_connections_name_each_end_by_element_and_connector(package):
    """Catches start and end swapped, or an element named where its connector belongs."""
    _, _, _, data = package
    connections = ET.fromstring(data["SystemStructure.ssd"]).find(f"{SSD}System/{SSD}Connections")
    assert [c.attrib for c in connections] == [
        {"startElement": "first", "startConnector": "y", "endElement": "second", "endConnector": "u"},
        {"startElement": "second", "startConnector": "y", "endElement": "third", "endConnector": "u"}]


def test_each_parameter_set_is_named_for_ecos_and_types_each_value(package):
    """Catches the set's name (Ecos selects it by name) or version changed, a value written
    under another type or in another spelling (FMI's ``true``, an Integer without a point)."""
    _, _, _, data = package
    for name, expected in (("first", [("gain", "Real", "1.5"), ("count", "Integer", "3")]),
                           ("third", [("flag", "Boolean", "true"), ("label", "String", "x")])):
        root = ET.fromstring(data[f"resources/{name}.ssv"])
        assert (root.tag, root.attrib) == (f"{SSV}ParameterSet", {"version": "1.0", "name": PARAMETER_SET})
        (parameters,) = list(root)
        assert parameters.tag == f"{SSV}Parameters"
        read = []
        for p in parameters:
            assert p.tag == f"{SSV}Parameter" and list(p.attrib) == ["name"]
            (typed,) = list(p)
            read.append((p.get("name"), typed.tag.removeprefix(SSV), typed.get("value")))
            assert list(typed.attrib) == ["value"]
        assert read == expected
    assert PARAMETER_SET == "parameters"


def test_the_archive_holds_exactly_its_members_fmus_stored_and_documents_compressed(package):
    """An FMU is a zip already: stored as it is; the XML deflated.  The package's mode is the
    user's umask's (a shared folder's reader can open it), and no temporary file is left.
    Catches an FMU or a ``.ssv`` too many or lost, a compression swapped, and a mkstemp's
    0600 kept."""
    baked, path, infos, _ = package
    fmus = ["first", "second", "third"] if baked else ["Alpha", "Beta"]
    assert sorted(infos) == sorted(["SystemStructure.ssd", *(f"resources/{n}.fmu" for n in fmus),
                                    "resources/first.ssv", "resources/third.ssv"])
    for name, info in infos.items():
        expected = zipfile.ZIP_STORED if name.endswith(".fmu") else zipfile.ZIP_DEFLATED
        assert info.compress_type == expected, name
    mask = os.umask(0o022)
    os.umask(mask)
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o666 & ~mask
    assert sorted(p.name for p in path.parent.iterdir()) == ["Loop.ssp"]


def test_an_output_connected_twice_and_recorded_is_one_output_connector(tmp_path):
    """One output feeding two inputs and recorded is declared three times, the same way each
    time: one connector, no refusal.  Catches a repeated declaration compared with something
    else than its kind and type (taken for a clash, "would be both ...") or written twice."""
    fmus = {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}
    system = System((Component("first", "Alpha"), Component("second", "Beta"), Component("third", "Beta")),
                    (Connection("first.y", "second.u"), Connection("first.y", "third.u")),
                    ("first.y", "third.u"), stop_time=STOP, step=STEP)
    path = export_ssp(system, tmp_path / "Fan.ssp", fmus=fmus, bake=False)
    with zipfile.ZipFile(path) as z:
        elements = ET.fromstring(z.read("SystemStructure.ssd")).find(f"{SSD}System/{SSD}Elements")
    connectors = {c.get("name"): [(k.get("name"), k.get("kind"), [t.tag for t in k])
                                  for k in c.iter(f"{SSD}Connector")] for c in elements}
    assert connectors == {"first": [("y", "output", [f"{SSC}Real"])], "second": [("u", "input", [f"{SSC}Real"])],
                          "third": [("u", "input", [f"{SSC}Real"])]}


def test_the_package_is_written_as_a_temporary_beside_it_named_after_it_then_renamed(tmp_path, monkeypatch):
    """The package appears whole or not at all: written to ``<package name>.<random>.tmp`` in
    its own folder, then renamed onto it (one rename, on one file system). The name starts with
    the package's name and a dot, so a write killed midway leaves a file that reads as that
    package's leftover (``Loop.ssp.*.tmp``), not as another package's (``Loop.ssp2...``).
    Catches the temporary written elsewhere, or its name run into the package's."""
    fmus = {model: fake_fmu(tmp_path / f"{model}.fmu", model) for model in ("Alpha", "Beta")}
    moves, replace = [], os.replace

    def spy(source, target):
        moves.append((os.fspath(source), os.fspath(target)))
        return replace(source, target)

    monkeypatch.setattr(export_module.os, "replace", spy)
    path = export_ssp(_system(), tmp_path / "out" / "Loop.ssp", fmus=fmus, bake=False)
    [(source, target)] = [(s, t) for s, t in moves if t == os.fspath(path)]
    assert os.path.dirname(source) == os.fspath(path.parent)
    assert re.fullmatch(r"Loop\.ssp\.[A-Za-z0-9_]+\.tmp", os.path.basename(source)), source
    assert sorted(p.name for p in path.parent.iterdir()) == ["Loop.ssp"]
