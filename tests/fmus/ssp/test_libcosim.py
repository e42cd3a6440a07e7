"""OSP libcosim (PyPI libcosimpy) runs an exported SSP package like the Jacobi master and
Ecos (fmus.ssp.libcosim).

libcosim can end the process (a segmentation fault for a package without a step size,
``abort`` for an FMU error while initialising on a worker thread), so every libcosim run
here is in a child process (``isolated=True`` or a script)."""
from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import textwrap
import zipfile

import numpy as np
import pytest

from fmus.ssp.libcosim import (libcosim_available,
                                  read_libcosim_step, simulate_ssp_libcosim, with_libcosim_annotation)
from fmus.cosim.master import simulate
from fmus.ssp.export import NS, OSP_NS, export_ssp
from fmus.ssp.run import ecos_available, simulate_ssp_ecos
from fmus.cosim.system import Component, System
from fmus.status import RunStatus
from scenarios.scenes.catalogue import get_scene

pytestmark = [pytest.mark.slow, pytest.mark.fmu, pytest.mark.tools]

STOP = 0.2          # s: a short copy of the scene keeps the file fast
TOL = 1e-9          # m
SIGNALS = ("plant.x", "plant.y")
REASON = libcosim_available()
needs_libcosim = pytest.mark.skipif(REASON is not None,
                                    reason=f"libcosimpy cannot be loaded ({REASON}): pip install libcosimpy")


@pytest.fixture(scope="module")
def fmu_dir(built_fmus):
    return next(iter(built_fmus.values())).parent


@pytest.fixture(scope="module")
def thesis(fmu_dir, tmp_path_factory):
    """(system, .ssp path, Jacobi master result) for a 0.2 s copy of thesis_sim_circle."""
    system = dataclasses.replace(get_scene("thesis_sim_circle").system, stop_time=STOP)
    path = export_ssp(system, tmp_path_factory.mktemp("libcosim") / "thesis.ssp", fmu_dir)
    reference = simulate(system, mode="fmu", coupling="jacobi", fmu_dir=fmu_dir)
    assert reference.completed, reference.error
    return system, path, reference


@pytest.fixture(scope="module")
def libcosim_run(thesis):
    if REASON is not None:
        pytest.skip(f"libcosimpy cannot be loaded ({REASON}): pip install libcosimpy")
    _, path, _ = thesis
    return simulate_ssp_libcosim(path, list(SIGNALS), isolated=True)


def test_annotated_package_keeps_the_literal_prefixes_and_the_schema(thesis, tmp_path):
    """libcosim's parser (boost property_tree) matches 'ssd:', 'ssc:', 'osp:' literally."""
    _, path, _ = thesis
    out = with_libcosim_annotation(path, tmp_path / "annotated.ssp", worker_threads=None)
    twice = with_libcosim_annotation(out, tmp_path / "twice.ssp", worker_threads=0)
    assert read_libcosim_step(path) == (1e-3, 0)        # export_ssp writes it: the calling thread
    assert read_libcosim_step(out) == (1e-3, None)
    assert read_libcosim_step(twice) == (1e-3, 0)
    with zipfile.ZipFile(twice) as zf, zipfile.ZipFile(path) as original:
        text = zf.read("SystemStructure.ssd").decode()
        assert sorted(zf.namelist()) == sorted(original.namelist())
    assert f'xmlns:osp="{OSP_NS}"' in text and text.count("<osp:FixedStepAlgorithm ") == 1
    assert '<ssc:Annotation type="com.opensimulationplatform">' in text
    from fmpy.ssp.ssd import read_ssd

    read_ssd(str(twice), validate=True)


# --- runs ---------------------------------------------------------------------------------

@needs_libcosim
def test_libcosim_matches_the_jacobi_master(thesis, libcosim_run):
    """Catches libcosim running the package otherwise than our Jacobi master (other parameters, initial
    outputs, times off k h)."""
    system, _, reference = thesis
    run = libcosim_run
    assert run.error is None and run.tool == "libcosim"
    assert len(run.time) == len(reference.time) == round(STOP / system.step) + 1   # t = 0, h, ..., 0.2
    np.testing.assert_allclose(run.time, np.arange(len(run.time)) * system.step, rtol=0, atol=1e-12)
    for s in SIGNALS:
        assert np.max(np.abs(run[s] - reference[s])) <= TOL, s


@needs_libcosim
def test_libcosim_matches_ecos(thesis, libcosim_run):
    """Catches an SSP package that libcosim and Ecos (both Jacobi) run differently."""
    reason = ecos_available()
    if reason is not None:
        pytest.skip(f"Ecos not available ({reason}): pip install ecospy and apt-get install libtbb12")
    _, path, _ = thesis
    ecos = simulate_ssp_ecos(path, list(SIGNALS))
    assert ecos.error is None and len(ecos.time) == len(libcosim_run.time)
    for s in SIGNALS:
        assert np.max(np.abs(libcosim_run[s] - ecos[s])) <= TOL, s


@needs_libcosim
def test_from_ssp_file_takes_the_step_from_the_annotation(fmu_dir, tmp_path):
    """libcosimpy's documented call without step_size works on an annotated package
    (without the annotation it dies with a segmentation fault), and applies the
    parameter set (the trajectory kind is a String parameter)."""
    system = System((Component("traj", "Trajectory", {"kind": "triangle"}),), (), ("traj.x_d",),
                    stop_time=0.005)
    path = export_ssp(system, tmp_path / "traj.ssp", fmu_dir)      # as exported, nothing added
    script = textwrap.dedent(f"""
        from libcosimpy.CosimExecution import CosimExecution
        from libcosimpy.CosimObserver import CosimObserver
        from libcosimpy.CosimLogging import log_output_level, CosimLogLevel
        log_output_level(CosimLogLevel.WARNING)
        ex = CosimExecution.from_ssp_file({str(path)!r})
        obs = CosimObserver.create_last_value()
        ex.add_observer(obs)
        assert ex.step(5)
        i = ex.slave_index_from_instance_name("traj")
        ref = {{v.name.decode(): v.reference for v in ex.slave_variables(i)}}["x_d"]
        print("RESULT", ex.status().current_time, repr(obs.last_real_values(i, [ref])[0]))
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    line = next(line for line in proc.stdout.splitlines() if line.startswith("RESULT"))
    current_ns, x_d = int(line.split()[1]), float(line.split()[2])
    reference = simulate(system, mode="fmu", coupling="jacobi", fmu_dir=fmu_dir)
    assert current_ns == 5_000_000
    assert x_d == reference["traj.x_d"][5]


@needs_libcosim
def test_a_refused_step_stops_the_run_like_the_master(fmu_dir, tmp_path):
    """The plant started out of reach refuses its first step (fmi2Discard): libcosim fails
    the step, the run keeps the t = 0 row and the reason from the plant's 'error'."""
    system = dataclasses.replace(get_scene("thesis_sim_circle").system, stop_time=0.01)
    components = tuple(dataclasses.replace(c, parameters={**c.parameters, "x0": 5.0}) if c.name == "plant" else c
                       for c in system.components)
    path = export_ssp(dataclasses.replace(system, components=components), tmp_path / "refusing.ssp", fmu_dir)
    run = simulate_ssp_libcosim(path, list(SIGNALS), isolated=True)
    assert str(run.error).startswith("plant refused the step from t = 0 s: initialisation refused: start point x0=5.0")
    assert (run.error.kind, run.error.instance, run.error.time) == (RunStatus.INITIALISATION, "plant", 0.0)
    assert len(run.time) == 1 and run.time[0] == 0.0


FAILER = '''
from pythonfmu import Fmi2Slave, Fmi2Causality, Fmi2Variability, Real, String


class Failer(Fmi2Slave):
    """Raises in exitInitializationMode (pythonfmu: fmi2Fatal) when mode == 'init_raise'."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.mode, self.y = "init_raise", 0.0
        self.register_variable(String("mode", causality=Fmi2Causality.parameter,
                                      variability=Fmi2Variability.fixed))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def exit_initialization_mode(self):
        if self.mode == "init_raise":
            raise RuntimeError("Failer: init_raise")

    def do_step(self, current_time, step_size):
        self.y = current_time + step_size
        return True
'''


@needs_libcosim
def test_an_fmu_error_while_initialising_is_a_failed_run_not_an_abort(tmp_path, monkeypatch):
    """On libcosim's worker threads it aborts the process; the runner steps on the
    calling thread (numWorkerThreads 0), where it is a failed first step."""
    from pythonfmu import FmuBuilder

    monkeypatch.setenv("TMPDIR", str(tmp_path))   # what the aborted process leaves behind

    script = tmp_path / "Failer.py"
    script.write_text(FAILER)
    fmu = FmuBuilder.build_FMU(script, dest=tmp_path)
    ssd = f"""<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="{NS['ssd']}" xmlns:ssc="{NS['ssc']}" version="1.0" name="failer">
  <ssd:System name="failer"><ssd:Elements>
    <ssd:Component name="bad" type="application/x-fmu-sharedlibrary" source="resources/Failer.fmu"/>
  </ssd:Elements></ssd:System>
  <ssd:DefaultExperiment startTime="0.0" stopTime="0.003"/>
</ssd:SystemStructureDescription>
"""
    path = tmp_path / "failer.ssp"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("SystemStructure.ssd", ssd)
        zf.write(fmu, "resources/Failer.fmu")
    run = simulate_ssp_libcosim(path, ["bad.y"], step_size=1e-3, isolated=True)
    assert str(run.error).startswith("libcosim could not initialise the FMUs: Model error")
    assert (run.error.kind, run.error.instance) == (RunStatus.INITIALISATION, None)
    assert "exitInitializationMode" in str(run.error) and len(run.time) == 0
    if (os.cpu_count() or 1) > 1:   # libcosim uses at most hardware_concurrency - 1 workers
        with pytest.raises(RuntimeError, match="exit status -6"):
            simulate_ssp_libcosim(path, ["bad.y"], step_size=1e-3, worker_threads=1, isolated=True)
