"""SSP 1.0 export (fmus.ssp.export): the package is well-formed and runs in fmpy's SSP runner and in
Ecos with the same end-effector trajectory as the Jacobi master, point for point."""
from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from fmus.cosim.master import simulate
from fmus.ssp.export import NS, PARAMETER_SET, export_ssp, read_ssp_experiment, read_ssp_parameters
from fmus.ssp.run import ecos_available, simulate_ssp_ecos, simulate_ssp_fmpy
from fmus.cosim.system import Component, Connection, System
from fmus.status import RunStatus
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant

pytestmark = [pytest.mark.slow, pytest.mark.fmu, pytest.mark.tools]

#: The bench with its drives inside the plant (ActuatedFiveBarPlant, RK4 x8) is exported too.
IN_PLANT = "bench_circle_TCMDx, drives in plant"
SCENES = ("thesis_sim_circle", "bench_circle_TCMDx", IN_PLANT)
STOP = 0.2          # s: a short copy of each scene keeps the file fast
TOL = 1e-9          # m
SIGNALS = ("plant.x", "plant.y")


def _short(name):
    scene = drives_in_plant(get_scene("bench_circle_TCMDx"), substeps=8) if name == IN_PLANT else get_scene(name)
    return dataclasses.replace(scene.system, stop_time=STOP)


@pytest.fixture(scope="module")
def fmu_dir(built_fmus):
    return next(iter(built_fmus.values())).parent


@pytest.fixture(scope="module", params=SCENES)
def exported(request, fmu_dir, tmp_path_factory):
    """(system, .ssp path, Jacobi master result through the same FMUs)."""
    system = _short(request.param)
    path = export_ssp(system, tmp_path_factory.mktemp("ssp") / f"{request.param.split(',')[0]}.ssp", fmu_dir)
    reference = simulate(system, mode="fmu", coupling="jacobi", fmu_dir=fmu_dir)
    assert reference.completed, reference.error
    return system, path, reference


def _compare(run, reference, h):
    """Max |run - master| over SIGNALS at the communication points both have."""
    k = np.round(run.time / h).astype(int)
    assert np.allclose(run.time, k * h, rtol=0, atol=1e-9), "run times are off the communication grid"
    common = (k >= 0) & (k < len(reference.time))
    assert common.sum() >= len(reference.time) - 1
    return max(float(np.max(np.abs(run[s][common] - reference[s][k[common]]))) for s in SIGNALS)


# --- the package -----------------------------------------------------------------------------

def test_ssd_is_well_formed(exported):
    """Catches an SSD with a wrong namespace, version, component order or connector declaration."""
    system, path, _ = exported
    with zipfile.ZipFile(path) as zf:
        names = set(zf.namelist())
        ssd = ET.fromstring(zf.read("SystemStructure.ssd"))
    assert ssd.tag == f"{{{NS['ssd']}}}SystemStructureDescription" and ssd.get("version") == "1.0"
    comps = {c.get("name"): c for c in ssd.iterfind("ssd:System/ssd:Elements/ssd:Component", NS)}
    assert list(comps) == [c.name for c in system.components]
    declared = {}
    for c in system.components:
        el = comps[c.name]
        assert el.get("source") == f"resources/{c.name}.fmu" and el.get("source") in names
        for conn in el.iterfind("ssd:Connectors/ssd:Connector", NS):
            types = [t.tag.split("}")[1] for t in conn]
            assert len(types) == 1 and types[0] in ("Real", "Integer", "Boolean", "String")
            declared[f"{c.name}.{conn.get('name')}"] = (conn.get("kind"), types[0])
    links = ssd.findall("ssd:System/ssd:Connections/ssd:Connection", NS)
    assert len(links) == len(system.connections)
    for link, conn in zip(links, system.connections):
        start = f"{link.get('startElement')}.{link.get('startConnector')}"
        end = f"{link.get('endElement')}.{link.get('endConnector')}"
        assert (start, end) == (conn.source, conn.target)
        assert declared[start][0] == "output" and declared[end][0] == "input"
        assert declared[start][1] == declared[end][1]
    # only connected inputs are connectors (fmpy's runner needs each one connected)
    inputs = {s for s, (kind, _) in declared.items() if kind == "input"}
    assert inputs == {c.target for c in system.connections}
    for signal in system.record:
        assert declared[signal][0] in ("output", "input")
    for c in system.components:
        for name in c.parameters:
            assert declared[f"{c.name}.{name}"][0] == "parameter"
    assert read_ssp_experiment(path) == (0.0, STOP, system.step)


def test_xml_members_are_utf8_text_files(exported):
    """Catches an SSD or SSV written without its UTF-8 XML declaration or without the final
    newline of a text file (the package's XML must diff and concatenate cleanly)."""
    _, path, _ = exported
    with zipfile.ZipFile(path) as zf:
        members = [n for n in zf.namelist() if n.endswith((".ssd", ".ssv"))]
        assert "SystemStructure.ssd" in members and len(members) >= 2
        for name in members:
            data = zf.read(name)
            assert data.startswith(b"<?xml version='1.0' encoding='UTF-8'?>\n"), name
            assert data.endswith(b">\n") and not data.endswith(b"\n\n"), name
            data.decode("utf-8")


def test_package_validates_against_the_ssp_schema(exported):
    """Catches an SSD or parameter file that breaks the SSP 1.0 schema (element order, a missing
    attribute), which strict tools refuse to load."""
    from fmpy.ssp.ssd import read_ssd

    _, path, _ = exported
    read_ssd(str(path), validate=True)  # also reads (and validates) every bound .ssv


def test_parameter_set_holds_the_scene_parameters(exported):
    """Catches a binding lost or retyped in the export (an Integer written as a Real, a Real not read back
    to the same double) or a parameter set a tool cannot select by its name."""
    system, path, _ = exported
    expected = {f"{c.name}.{n}": v for c in system.components for n, v in c.parameters.items()}
    got = read_ssp_parameters(path)
    assert got == expected
    for name, value in expected.items():
        # Strings stay strings, integers integers, Reals read back to the same double.
        assert type(got[name]) is (float if isinstance(value, float) else type(value)), name
    with zipfile.ZipFile(path) as zf:
        for c in system.components:
            if c.parameters:
                ssv = ET.fromstring(zf.read(f"resources/{c.name}.ssv"))
                assert ssv.tag == f"{{{NS['ssv']}}}ParameterSet" and ssv.get("name") == PARAMETER_SET


def test_each_instance_fmu_starts_at_its_parameters(exported):
    """The parameters are baked into each instance's FMU copy: its model description's start
    values and the start_values.json its slave reads equal the bound parameter set."""
    import json

    system, path, _ = exported
    bound = read_ssp_parameters(path)
    with zipfile.ZipFile(path) as zf:
        for c in system.components:
            with zipfile.ZipFile(zf.open(f"resources/{c.name}.fmu")) as fmu:
                baked = json.loads(fmu.read("resources/start_values.json"))
                md = ET.fromstring(fmu.read("modelDescription.xml"))
            assert {f"{c.name}.{k}": v for k, v in baked.items()} == \
                {k: v for k, v in bound.items() if k.startswith(f"{c.name}.")}
            starts = {sv.get("name"): next(iter(sv)).get("start") for sv in md.iter("ScalarVariable")}
            for name, value in baked.items():
                expected = ("true" if value else "false") if isinstance(value, bool) else (
                    repr(value) if isinstance(value, float) else str(value))
                assert starts[name] == expected


def test_plain_fmpy_runs_the_package_without_its_parameter_bindings(exported):
    """fmpy's simulate_ssp ignores parameter bindings; with the baked start values its plain
    run (no parameter_set, fmpy's own zero start of the connectors) equals the run given
    the bindings."""
    from fmpy.ssp.simulation import simulate_ssp

    system, path, _ = exported
    plain = simulate_ssp(str(path), stop_time=system.stop_time, step_size=system.step)
    bound = simulate_ssp_fmpy(path, initial_outputs=False)
    for s in SIGNALS:
        assert np.array_equal(plain[s], bound[s])


def test_string_and_boolean_parameters_round_trip(fmu_dir, tmp_path):
    """Catches Strings with XML special characters or Booleans and Integers that do not read back as
    written."""
    system = System(
        (Component("plant", "FiveBarPlant", {"preset": "bench", "project": True, "encoder_counts": 4000,
                                             "x0": -0.002, "y0": 0.108, "kernel": 'a "quoted" & <odd>'}),),
        (), ("plant.x",), stop_time=0.01)
    got = read_ssp_parameters(export_ssp(system, tmp_path / "p.ssp", fmu_dir))
    assert got == {"plant.preset": "bench", "plant.project": True, "plant.encoder_counts": 4000,
                   "plant.x0": -0.002, "plant.y0": 0.108, "plant.kernel": 'a "quoted" & <odd>'}


# --- running it elsewhere --------------------------------------------------------------------

def test_fmpy_simulate_ssp_matches_the_jacobi_master(exported):
    """Catches fmpy's runner given other parameters, initial outputs or time labels than our Jacobi master
    (its row k is the master's row k + 1)."""
    system, path, reference = exported
    run = simulate_ssp_fmpy(path)
    # fmpy labels the values after the step [t, t + h] with t and has no row for t = 0:
    # its row k is the master's row k + 1.
    np.testing.assert_allclose(run.extra["fmpy_time_labels"][:3], [0.0, system.step, 2 * system.step])
    np.testing.assert_allclose(run.time[0], system.step)
    assert _compare(run, reference, system.step) <= TOL


def test_fmpy_without_initial_outputs_starts_from_zero_inputs(exported):
    """fmpy's own runner starts every connector at 0.0: the first step then reads zeros, so
    the trajectory departs from the master's; simulate_ssp_fmpy corrects that by default."""
    system, path, reference = exported
    run = simulate_ssp_fmpy(path, initial_outputs=False)
    assert _compare(run, reference, system.step) > 1e-6


def test_ecos_matches_the_jacobi_master(exported):
    """Catches Ecos run with other parameters (a parameter set it did not apply) or its rows read at other
    times than our Jacobi master's."""
    reason = ecos_available()
    if reason is not None:
        pytest.skip(f"Ecos not available ({reason}): pip install ecospy and apt-get install libtbb12")
    system, path, reference = exported
    run = simulate_ssp_ecos(path, list(SIGNALS))
    # Ecos: row 0 after initialisation (t = 0), row k after the k-th step: the master's rows.
    assert len(run.time) == len(reference.time)
    np.testing.assert_allclose(run.time, reference.time, rtol=0, atol=1e-12)
    assert _compare(run, reference, system.step) <= TOL


# --- what cannot be exported -----------------------------------------------------------------

def _system(**changes):
    base = dict(components=(Component("traj", "Trajectory", {"kind": "circle"}),
                            Component("ctrl", "PositionController", {"strategy": "PDq"})),
                connections=(Connection("traj.x_d", "ctrl.x_d"),), record=("ctrl.tau1",), stop_time=0.1)
    base.update(changes)
    return System(**base)


@pytest.mark.parametrize("changes, message", [
    ({"components": (Component("traj", "Trajectory", substeps=2),)
      , "connections": (), "record": ()}, "substeps"),
    ({"components": (Component("traj", "NoSuchModel"),), "connections": (), "record": ()}, "NoSuchModel"),
    ({"record": ("ctrl.nothing",)}, "no variable 'nothing'"),
    ({"record": ("ctrl.q1",)}, "only outputs and connected inputs"),
    ({"connections": (Connection("ctrl.x_d", "traj.x_d"),)}, "not an output"),
    ({"components": (Component("traj", "Trajectory", {"kind": 3}),
                     Component("ctrl", "PositionController"))}, "no String value"),
    ({"components": (Component("traj", "Trajectory", {"cycles": 1.5}),
                     Component("ctrl", "PositionController"))}, "no Integer value"),
    ({"components": (Component("traj", "Trajectory", {"side_time": float("nan")}),
                     Component("ctrl", "PositionController"))}, "not finite"),
    ({"components": (Component("traj", "Trajectory", {"x_d": 0.1}),
                     Component("ctrl", "PositionController"))}, "not a parameter"),
])
def test_what_cannot_be_exported_is_a_value_error(fmu_dir, tmp_path, changes, message):
    """Catches an export that writes a package a tool cannot run (sub-steps, an unknown model, a recorded
    input, a wrong connection or parameter type), or leaves a partial file behind."""
    with pytest.raises(ValueError, match=message):
        export_ssp(_system(**changes), tmp_path / "bad.ssp", fmu_dir)
    assert not (tmp_path / "bad.ssp").exists()


def test_an_ssp_path_must_end_in_ssp(fmu_dir, tmp_path):
    with pytest.raises(ValueError, match=r"\.ssp"):
        export_ssp(_system(), tmp_path / "bad.zip", fmu_dir)


# --- a refused step ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def refusing(fmu_dir, tmp_path_factory):
    """The thesis scene with the plant started out of reach: it refuses every step."""
    system = _short("thesis_sim_circle")
    components = tuple(dataclasses.replace(c, parameters={**c.parameters, "x0": 5.0}) if c.name == "plant" else c
                       for c in system.components)
    system = dataclasses.replace(system, components=components, stop_time=0.01)
    return export_ssp(system, tmp_path_factory.mktemp("ssp") / "refusing.ssp", fmu_dir)


def test_fmpy_run_that_an_fmu_refuses_names_the_reason(refusing):
    """Catches fmpy's exception on fmi2Discard escaping the runner, or its error given as text: fmpy's
    rows are lost, so the run has none, and its error is the plant's record (initialisation, t = 0)."""
    run = simulate_ssp_fmpy(refusing)
    assert (run.error.kind, run.error.instance, run.error.time) == (RunStatus.INITIALISATION, "plant", 0.0)
    assert "initialisation refused: start point x0=5.0" in str(run.error) and len(run.time) == 0


def test_ecos_run_stops_at_a_refused_step_like_the_master(refusing):
    """Catches an Ecos run that steps on past a refusal (Ecos does) or loses the plant's record; it keeps
    the master's single row."""
    reason = ecos_available()
    if reason is not None:
        pytest.skip(f"Ecos not available ({reason}): pip install ecospy and apt-get install libtbb12")
    run = simulate_ssp_ecos(refusing, list(SIGNALS))
    assert str(run.error).startswith("plant refused the step from t = 0 s: initialisation refused")
    assert (run.error.kind, run.error.instance) == (RunStatus.INITIALISATION, "plant")
    assert len(run.time) == 1 and run.time[0] == 0.0   # the master keeps the same single row


def test_fmpy_gives_each_instance_its_own_parameters(fmu_dir, tmp_path):
    """fmpy matches parameters to instances by bare name prefix ("traj" would take "traj2.*")."""
    system = System((Component("traj", "Trajectory", {"kind": "thesis_circle"}),
                     Component("traj2", "Trajectory", {"kind": "triangle"})),
                    (), ("traj.x_d", "traj2.x_d"), stop_time=0.01)
    run = simulate_ssp_fmpy(export_ssp(system, tmp_path / "two.ssp", fmu_dir))
    reference = simulate(system, mode="fmu", coupling="jacobi", fmu_dir=fmu_dir)
    n = min(len(run.time), len(reference.time) - 1)
    for signal in system.record:
        np.testing.assert_array_equal(run[signal][:n], reference[signal][1:n + 1])
    assert run["traj.x_d"][0] != run["traj2.x_d"][0]
