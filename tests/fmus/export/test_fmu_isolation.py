"""An FMU's Python code is its own and stays out of the importer's way (issue 30, items 3-4).

The bundled model code runs under a private package ``parcosim_<hash>`` (fmus/export/bundle.py),
loaded by parcosim's wrapper without ``sys.path``; the wrapper checks the GUID and the binary
against the identity in the resources, and the slaves refuse FMI calls out of order.  Cases
that depend on what a process has imported run in fresh processes (a case that crashes the
importer fails its test, not pytest).
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest

from fmus.export.bundle import PACKAGES, REWRITTEN, bundle_name, rewrite_imports
from fmus.export.wrapper import compiled_wrapper
from tests.fmus.export.test_wrapper import run_case, unzip
from tests.support.paths import ROOT

pytestmark = [pytest.mark.fmu]

#: The names the bundle must never add to an importer's sys.modules.
PLAIN = ("plant", "motor", "controller", "fmus", "scenarios", "parcosim")
needs_wrapper = pytest.mark.skipif(compiled_wrapper(quiet=True) is None,
                                   reason="no C compiler: the FMUs keep pythonfmu's wrapper")


def run_python(code: str, cwd, timeout: float = 300):
    """Run ``code`` in a fresh Python in ``cwd`` (no PYTHONPATH: what it imports is what the code
    and ``cwd`` give); it must exit 0; the JSON of its last line of output."""
    env = {name: value for name, value in os.environ.items() if name != "PYTHONPATH"}
    run = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd, env=env, capture_output=True,
                         text=True, timeout=timeout)
    assert run.returncode == 0, f"exit {run.returncode}\n{run.stdout[-2000:]}\n{run.stderr[-3000:]}"
    return json.loads(run.stdout.strip().splitlines()[-1])


# --- the rewriting ---------------------------------------------------------------------------------

def test_every_import_form_is_rewritten_and_binds_what_it_bound(tmp_path):
    """Absolute imports (plain, dotted, aliased, lazy, in a one-line block) of the bundled names
    become imports of the private package; relative and other imports stay; the names bound are
    the same modules."""
    source = textwrap.dedent("""\
        import os, plant.fast5r
        import motor as m, controller
        from fmus.slave.base import (MIN_STEP,
                                     FmiError)  # a comment stays
        from . import sibling
        def lazy():
            from plant.spec import load; return load
        if True: import fmus.slave.declarations as parts
        """).encode()
    out = rewrite_imports(source, "P").decode()
    assert out.splitlines()[0] == "import os, P.plant.fast5r, P.plant as plant"
    assert "import P.motor as m, P.controller as controller" in out
    assert "from P.fmus.slave.base import (MIN_STEP,\n                             FmiError)  # a comment stays" in out
    assert "from . import sibling" in out and "from P.plant.spec import load; return load" in out
    assert "if True: import P.fmus.slave.declarations as parts" in out
    assert out.count("\n") == source.decode().count("\n")        # line numbers kept
    # Executed against a package P holding a plant.fast5r, the names bind to P's modules.
    package = tmp_path / "P" / "plant"
    package.mkdir(parents=True)
    (tmp_path / "P" / "__init__.py").write_text("")
    (package / "__init__.py").write_text("")
    (package / "fast5r.py").write_text("KERNEL = 'P'\n")
    code = rewrite_imports(b"import plant.fast5r\nvalue = plant.fast5r.KERNEL\n", "P").decode()
    result = run_python(f"""
        import json, sys
        sys.path.insert(0, {str(tmp_path)!r})
        namespace = {{}}
        exec({code!r}, namespace)
        print(json.dumps([namespace["value"], namespace["plant"].__name__, "plant" in sys.modules]))
    """, cwd=tmp_path)
    assert result == ["P", "P.plant", False]


def test_no_bundled_source_keeps_an_import_of_a_plain_name(tmp_path):
    """Catches a bundled module importing "plant" or "fmus" by its plain name, which would load another
    FMU's (or the host's) copy of parcosim in the same process."""
    from fmus.export.bundle import write_bundle

    package = write_bundle(tmp_path)
    assert package.name == bundle_name() and package.name.startswith("parcosim_")
    import ast

    for path in package.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_bytes())):
            names = [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 else \
                [a.name for a in node.names] if isinstance(node, ast.Import) else []
            assert not [n for n in names if n and n.split(".")[0] in REWRITTEN], f"{path}:{node.lineno}"


def test_the_name_follows_the_sources(tmp_path, monkeypatch):
    """Any source change gives another package name; the same sources the same one."""
    import fmus.export.bundle as bundle

    for name in (*PACKAGES, "fmus"):
        shutil.copytree(ROOT / name, tmp_path / name, ignore=shutil.ignore_patterns("__pycache__", "build"))
    monkeypatch.setattr(bundle, "ROOT", tmp_path)
    same = bundle.bundle_name()
    assert same == bundle_name()
    path = tmp_path / "motor" / "presets.py"
    path.write_text(path.read_text() + "\n")
    assert bundle.bundle_name() != same


# --- the importer's process ------------------------------------------------------------------------

@needs_wrapper
def test_a_fresh_process_keeps_its_modules_and_path_over_extractions(built_fmus, tmp_path):
    """Three extractions of one FMU (each deleted after its run), then another FMU type of the same
    build, whose modules are found in its own folder although the bundle was first loaded from a
    folder that is gone: right outputs, no plain name in sys.modules, sys.path unchanged."""
    result = run_python(f"""
        import json, sys
        import fmpy
        path = list(sys.path)
        x = [float(fmpy.simulate_fmu({str(built_fmus['Trajectory'])!r}, stop_time=0.003, step_size=1e-3,
                                     start_values={{'kind': 'hold'}})['x_d'][-1]) for _ in range(3)]
        i = fmpy.simulate_fmu({str(built_fmus['DCMotorDrive'])!r}, stop_time=0.02, step_size=1e-3,
                              start_values={{'mode': 'voltage', 'v_ref': 6.0, 'preset': 'motor2'}})['i'][-1]
        print(json.dumps({{"x": x, "i": float(i), "plain": [m for m in {PLAIN!r} if m in sys.modules],
                          "same_path": sys.path == path,
                          "bundles": sorted({{m.split('.')[0] for m in sys.modules if m.startswith('parcosim_')}})}}))
    """, cwd=tmp_path)
    assert result["x"] == [-0.002] * 3
    assert result["i"] == pytest.approx(6.0 / 0.829, rel=1e-9)
    assert result["plain"] == [] and result["same_path"]
    assert result["bundles"] == [bundle_name()]


@needs_wrapper
def test_an_importers_own_controller_package_is_left_alone(built_fmus, tmp_path):
    """A package ``controller`` of the importer's, on its sys.path: the FMU (whose code has its
    own ``controller``) runs, and the importer's package is what ``import controller`` gives,
    imported after the FMU ran and before it runs again."""
    mine = tmp_path / "mine" / "controller"
    mine.mkdir(parents=True)
    (mine / "__init__.py").write_text("OWNER = 'the importer'\n")
    result = run_python(f"""
        import json, sys
        import fmpy
        sys.path.insert(0, {str(mine.parent)!r})
        run = lambda: float(fmpy.simulate_fmu({str(built_fmus['Trajectory'])!r}, stop_time=0.002, step_size=1e-3,
                                              start_values={{'kind': 'hold', 'x_hold': 0.01}})['x_d'][-1])
        first = run()
        import controller
        second = run()
        print(json.dumps([first, second, controller.OWNER, sys.modules['controller'] is controller,
                          controller.__file__]))
    """, cwd=tmp_path)
    assert result[:4] == [0.01, 0.01, "the importer", True] and result[4].startswith(str(mine))


@needs_wrapper
def test_with_parcosim_imported_the_fmu_runs_its_own_bundle(built_fmus, tmp_path):
    """The repository's packages imported first: the FMU's modules are still those of its
    extraction folder, and the importer's are untouched."""
    where = unzip(built_fmus["Trajectory"], tmp_path / "Trajectory")
    package = bundle_name()
    result = run_python(f"""
        import json, sys
        import fmpy
        import controller.trajectories, fmus.slave.base
        mine = (controller.trajectories.__file__, fmus.slave.base.__file__)
        fmpy.simulate_fmu({str(where)!r}, stop_time=0.002, step_size=1e-3)
        theirs = sys.modules["{package}.controller.trajectories"]
        print(json.dumps([theirs.__file__, sys.modules["{package}.fmus.slave.base"].__file__,
                          (controller.trajectories.__file__, fmus.slave.base.__file__) == mine,
                          sys.modules["controller.trajectories"] is controller.trajectories]))
    """, cwd=ROOT)
    resources = str(where / "resources" / package)
    assert result[0].startswith(resources) and result[1].startswith(resources)
    assert result[2] and result[3]


def _build_from_copy(tmp_path, edit) -> Path:
    """Trajectory.fmu built from a copy of the sources changed by ``edit(copy)``."""
    copy = tmp_path / "sources"
    for name in (*PACKAGES, "fmus"):
        shutil.copytree(ROOT / name, copy / name, ignore=shutil.ignore_patterns("__pycache__", "build"))
    edit(copy)
    out = tmp_path / "out"
    run_python(f"""
        import json
        from fmus.export.build import build_fmu
        print(json.dumps(str(build_fmu("Trajectory", {str(out)!r}))))
    """, cwd=copy)
    return out / "Trajectory.fmu"


@pytest.fixture(scope="module")
def other_version(tmp_path_factory) -> Path:
    """Trajectory.fmu built from sources whose bench start point is x = -0.003 m (-0.002 m here)."""
    def edit(copy):
        path = copy / "controller" / "trajectories.py"
        text = path.read_text()
        assert "BENCH_START = (-0.002, 0.108)" in text
        path.write_text(text.replace("BENCH_START = (-0.002, 0.108)", "BENCH_START = (-0.003, 0.108)"))
    return _build_from_copy(tmp_path_factory.mktemp("version"), edit)


@needs_wrapper
def test_two_fmus_built_from_different_versions_coexist_in_one_process(built_fmus, other_version, tmp_path):
    """Each runs its own code: the start point each holds by default is its own version's."""
    result = run_python(f"""
        import json, sys
        sys.path.insert(0, {str(ROOT / 'tests' / 'support')!r})
        from fmi_support import FmuInstance
        a = FmuInstance({str(built_fmus['Trajectory'])!r}, {{"kind": "hold"}}, "a")
        b = FmuInstance({str(other_version)!r}, {{"kind": "hold"}}, "b")
        for _ in range(3):
            a.step(1e-3)
            b.step(1e-3)
        print(json.dumps([a.get("x_d"), b.get("x_d"), a.get("x_start"), b.get("x_start"),
                          sorted({{m.split('.')[0] for m in sys.modules if m.startswith('parcosim_')}})]))
    """, cwd=tmp_path)
    assert result[:4] == [-0.002, -0.003, -0.002, -0.003]
    assert len(result[4]) == 2 and bundle_name() in result[4]


@needs_wrapper
def test_two_fmu_types_instantiate_and_step_at_once_from_two_threads(built_fmus, tmp_path):
    """Before: 3 of 3 runs failed (the controller's initialisation saw a partially initialised
    ``motor.presets`` imported by the drive's thread).  Each run is a fresh process (imports
    happen once per process)."""
    folders = [unzip(built_fmus[m], tmp_path / m) for m in ("PositionController", "DCMotorDrive")]
    code = f"""
        import json, threading
        from fmpy import read_model_description
        from fmpy.fmi2 import FMU2Slave
        folders = {[str(f) for f in folders]!r}
        barrier, out = threading.Barrier(2), [None, None]
        # fmpy's reader validates against the FMI schema with lxml, which is not thread-safe
        # (seen once in CI: XMLSchemaParseError): the importer's part is read before the threads.
        descriptions = [read_model_description(folder) for folder in folders]
        def run(k):
            try:
                md = descriptions[k]
                fmu = FMU2Slave(guid=md.guid, unzipDirectory=folders[k], instanceName=f"i{{k}}",
                                modelIdentifier=md.coSimulation.modelIdentifier)
                barrier.wait()
                fmu.instantiate()
                fmu.setupExperiment(startTime=0.0)
                fmu.enterInitializationMode()
                fmu.exitInitializationMode()
                for n in range(5):
                    fmu.doStep(currentCommunicationPoint=n * 1e-3, communicationStepSize=1e-3)
                out[k] = "ok"
                fmu.terminate()
                fmu.freeInstance()
            except Exception as exc:
                out[k] = repr(exc)
        threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
        for t in threads: t.start()
        for t in threads: t.join()
        print(json.dumps(out))
    """
    for _ in range(3):
        assert run_python(code, cwd=tmp_path) == ["ok", "ok"]


@needs_wrapper
def test_pythonfmus_binary_still_runs_the_bundle(built_fmus, tmp_path):
    """Without a C compiler an FMU keeps pythonfmu's binary: it finds the dotted slave module.

    The child leaves by ``os._exit`` once its answer is out: pythonfmu 0.7.0's binary corrupts the heap in
    its teardown at interpreter exit, now and then ("corrupted double-linked list", exit -6 after the right
    answer: 1 run in 6 here), whatever the bundle; docs/bundle.md lists it.  parcosim's own wrapper, built
    wherever a C compiler is, has no such teardown."""
    import pythonfmu

    from fmus.export.archive import rewrite

    fmu = rewrite(built_fmus["Trajectory"], tmp_path / "Trajectory.fmu", {
        "binaries/linux64/Trajectory.so": (Path(pythonfmu.__file__).parent / "resources" / "binaries" / "linux64"
                                           / "libpythonfmu-export.so").read_bytes()})
    result = run_python(f"""
        import json, sys
        import fmpy
        r = fmpy.simulate_fmu({str(fmu)!r}, stop_time=0.002, step_size=1e-3, start_values={{'kind': 'hold'}})
        print(json.dumps([float(r['x_d'][-1]), [m for m in {PLAIN!r} if m in sys.modules]]), flush=True)
        import os
        os._exit(0)
    """, cwd=tmp_path)
    assert result == [-0.002, []]


# --- the FMU's identity ------------------------------------------------------------------------------

def test_the_identity_names_the_fmus_guid_binary_and_bundle(built_fmus):
    """Catches an FMU whose identity file names another model, GUID or bundle than its modelDescription and
    slave module."""
    from fmpy import read_model_description

    for model, path in built_fmus.items():
        md = read_model_description(str(path), validate=False)
        with zipfile.ZipFile(path) as z:
            identity = json.loads(z.read("resources/parcosim_build.json"))
            slave_module = z.read("resources/slavemodule.txt").decode()
        assert identity == {"model": model, "built_by": "parcosim", "package": bundle_name(), "guid": md.guid,
                            "model_identifier": md.coSimulation.modelIdentifier}
        assert slave_module.startswith(f"{bundle_name()}.fmus.slaves.parcosim_")


def test_a_slave_knows_its_fmus_guid(built_fmus, tmp_path):
    """From the identity in its resources; "" in process."""
    from fmpy import read_model_description

    from fmus.slaves.parcosim_trajectory import Trajectory

    where = unzip(built_fmus["Trajectory"], tmp_path / "Trajectory")
    assert Trajectory(instance_name="t", resources=str(where / "resources")).fmu_guid == \
        read_model_description(str(where)).guid
    assert Trajectory(instance_name="t").fmu_guid == ""


@needs_wrapper
def test_a_guid_that_is_not_the_fmus_is_refused_naming_both(built_fmus, tmp_path):
    """Catches fmi2Instantiate accepting a GUID of another FMU (a modelDescription and binary that do not
    match), or refusing its own afterwards."""
    where = unzip(built_fmus["Trajectory"], tmp_path / "Trajectory")
    result = run_case(f"""
        fmu = RawFmu({str(where)!r})
        own = fmu.guid
        fmu.guid = "{{00000000-0000-0000-0000-000000000000}}"
        refused = fmu.instantiate()
        fmu.guid = own
        report(refused=refused, text=fmu.text(), own=own, ok=bool(fmu.instantiate()), statuses=fmu.start())
    """)
    assert result["refused"] is None and result["ok"] and result["statuses"] == [0, 0, 0]
    assert "GUID '{00000000-0000-0000-0000-000000000000}' is not this FMU's" in result["text"]
    assert f"has GUID '{result['own']}'" in result["text"]


@needs_wrapper
def test_resources_of_another_fmu_are_refused_before_any_of_their_code_runs(built_fmus, tmp_path):
    """Catches a binary that imports another FMU's bundled Python code from a resource URI before checking
    whose resources they are."""
    trajectory = unzip(built_fmus["Trajectory"], tmp_path / "Trajectory")
    drive = unzip(built_fmus["DCMotorDrive"], tmp_path / "DCMotorDrive")
    result = run_case(f"""
        fmu = RawFmu({str(trajectory)!r})
        refused = fmu.instantiate(uri={(drive / "resources").as_uri().encode() + b"/"!r})
        report(refused=refused, text=fmu.text(), loaded=[m for m in sys.modules if m.startswith("parcosim_")])
    """)
    assert result["refused"] is None and result["loaded"] == []
    assert "belong to the FMU 'DCMotorDrive'" in result["text"] and "not to this binary (Trajectory)" in result["text"]


@needs_wrapper
def test_resources_of_another_build_of_the_same_model_are_refused(built_fmus, other_version, tmp_path):
    """Catches a binary that loads the resources of another build of the same model (another version of the
    code)."""
    ours = unzip(built_fmus["Trajectory"], tmp_path / "ours")
    theirs = unzip(other_version, tmp_path / "theirs")
    result = run_case(f"""
        fmu = RawFmu({str(ours)!r})
        refused = fmu.instantiate(uri={(theirs / "resources").as_uri().encode() + b"/"!r})
        report(refused=refused, text=fmu.text(), own=fmu.guid)
    """)
    assert result["refused"] is None and f"GUID '{result['own']}' is not this FMU's" in result["text"]


# --- the FMI call order ------------------------------------------------------------------------------

@needs_wrapper
def test_calls_out_of_order_are_refused_and_change_nothing(built_fmus, tmp_path):
    """FMI 2.0's co-simulation state machine: fmi2SetupExperiment and fmi2EnterInitializationMode
    once, before initialisation; fmi2ExitInitializationMode only in Initialization Mode.  Each call
    out of order is fmi2Error naming it, and the instance then steps exactly as one that never saw
    them (before: fmi2ExitInitializationMode in Step Mode returned fmi2OK and rebuilt the model)."""
    where = unzip(built_fmus["DCMotorDrive"], tmp_path / "DCMotorDrive")
    result = run_case(f"""
        from ctypes import byref, c_double
        def start(fmu, hostile):
            lib, c = fmu.lib, fmu.c
            statuses = [lib.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), lib.fmi2EnterInitializationMode(c)]
            if hostile:
                statuses += [lib.fmi2EnterInitializationMode(c), lib.fmi2SetupExperiment(c, 0, 0.0, 5.0, 0, 0.0)]
            statuses += [fmu.set_string(fmu.vars["mode"][0], b"voltage"), fmu.set_real(fmu.vars["v_ref"][0], 6.0),
                         lib.fmi2ExitInitializationMode(c)]
            return statuses
        def run(hostile):
            fmu = RawFmu({str(where)!r})
            fmu.instantiate()
            statuses = start(fmu, hostile)
            for k in range(6):
                if hostile and k == 3:
                    statuses += [fmu.lib.fmi2ExitInitializationMode(fmu.c), fmu.lib.fmi2EnterInitializationMode(fmu.c),
                                 fmu.lib.fmi2SetupExperiment(fmu.c, 0, 0.0, 7.0, 0, 0.0)]
                statuses.append(fmu.step(k * 1e-3, 1e-3))
            last = c_double()
            statuses.append(fmu.lib.fmi2GetRealStatus(fmu.c, 2, byref(last)))
            return statuses, fmu.get_real(fmu.vars["i"][0])[1], last.value, fmu.text()
        report(clean=run(False), hostile=run(True))
    """)
    clean, hostile = result["clean"], result["hostile"]
    assert clean[0] == [0] * 5 + [0] * 6 + [0]
    assert hostile[0] == [0, 0, 3, 3, 0, 0, 0] + [0, 0, 0, 3, 3, 3, 0, 0, 0] + [0]
    assert hostile[1] == clean[1] and hostile[2] == clean[2] == pytest.approx(6e-3)
    text = hostile[3]
    assert "fmi2EnterInitializationMode refused in Initialization Mode" in text
    assert "fmi2SetupExperiment (start_time = 5.0) refused in Initialization Mode" in text
    assert "fmi2ExitInitializationMode refused in Step Mode (at t = 0.003 s)" in text
    assert "fmi2SetupExperiment (start_time = 7.0) refused in Step Mode" in text
    assert "nothing was changed" in text


def test_in_process_the_slave_refuses_the_same_calls():
    """Catches the in-process slave accepting calls out of order that the FMU's wrapper refuses, so the two
    back ends would behave differently."""
    from fmus.slave.base import FmiError
    from tests.fmus.slave.test_extremes import make_slave

    slave = make_slave("Derivator")
    with pytest.raises(FmiError, match="fmi2ExitInitializationMode refused in Step Mode"):
        slave.exit_initialization_mode()
    with pytest.raises(FmiError, match=r"fmi2SetupExperiment \(start_time = 1.0\) refused in Step Mode"):
        slave.setup_experiment(1.0)
    slave.terminate()
    with pytest.raises(FmiError, match="fmi2EnterInitializationMode refused after fmi2Terminate"):
        slave.enter_initialization_mode()
    fresh = type(slave)(instance_name="d")
    with pytest.raises(FmiError, match="fmi2ExitInitializationMode refused before fmi2EnterInitializationMode"):
        fresh.exit_initialization_mode()
    assert not fresh._initialised
